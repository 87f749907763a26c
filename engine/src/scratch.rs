//! The operators' scratch buffers and the tiles that size them: a scan's levels of partial
//! sums; a radix sort's other keys and values, its tiles' digit histograms and their partial
//! sums. Resolve sizes them and reports name them; the operator kernels ([`crate::scan`],
//! [`crate::radix`]) number them the same way.

use crate::limits::{Target, WORKGROUP};
use crate::operator::OpKind;

/// Bits of a digit of the portable sort (its scatter packs the counts of the 16 digits into
/// two vectors of four words).
pub const DIGIT_BITS: u32 = 4;
/// Elements each thread of a portable sort pass ranks.
pub const SORT_ITEMS: u32 = 8;
/// Bits of a digit of the sort ranked by subgroup ballots.
pub const BALLOT_DIGIT_BITS: u32 = 8;
/// Most elements each thread of a ballot-ranked sort pass may rank (a tile's digit counts fit
/// 16 bits).
pub const BALLOT_ITEMS: u32 = 16;
/// Fewest elements a thread of a ballot-ranked sort ranks: with less workgroup memory than
/// this needs, the target sorts the portable way.
const BALLOT_MIN_ITEMS: u32 = 4;

/// How a target's radix sort runs: the digits of a pass, the elements each thread ranks, and
/// whether subgroup ballots rank them (8-bit digits, a row of digit counts per subgroup in
/// workgroup memory) or per-thread counts do (4-bit digits, any adapter).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SortShape {
    /// Bits of a digit.
    pub digit_bits: u32,
    /// Elements each thread ranks.
    pub items: u32,
    /// Rows of digit counts, one per subgroup a workgroup may hold; 0 for the portable sort.
    pub rows: u32,
}

impl SortShape {
    /// The portable shape.
    pub const PORTABLE: SortShape = SortShape {
        digit_bits: DIGIT_BITS,
        items: SORT_ITEMS,
        rows: 0,
    };

    /// The shape `target` sorts with: ballots where it has subgroups and the workgroup memory
    /// for a row per subgroup plus a tile of at least [`BALLOT_MIN_ITEMS`] elements a thread
    /// (at most its `sort_items`).
    pub fn of(target: &Target) -> SortShape {
        let radix = 1u32 << BALLOT_DIGIT_BITS;
        let min = target.subgroup_min_size.max(1);
        if !target.subgroups() || !WORKGROUP.is_multiple_of(target.subgroup_max_size.max(1)) || WORKGROUP < min {
            return SortShape::PORTABLE;
        }
        let rows = WORKGROUP / min;
        // Rows of 16-bit counts, the digits' starts and offsets, the subgroups' sums.
        let fixed = 4 * (rows * radix / 2 + 2 * radix + rows);
        let items = (target.workgroup_bytes.saturating_sub(fixed) / (4 * WORKGROUP))
            .min(target.sort_items)
            .min(BALLOT_ITEMS);
        if items < BALLOT_MIN_ITEMS {
            return SortShape::PORTABLE;
        }
        SortShape {
            digit_bits: BALLOT_DIGIT_BITS,
            items,
            rows,
        }
    }

    /// Digits of a pass.
    pub fn radix(&self) -> u64 {
        1 << self.digit_bits
    }

    /// Elements of a tile: one workgroup ranks them together.
    pub fn tile(&self) -> u64 {
        (WORKGROUP * self.items) as u64
    }

    /// Passes of a sort by the low `bits` bits.
    pub fn passes(&self, bits: u32) -> u32 {
        bits.div_ceil(self.digit_bits)
    }

    /// Whether subgroup ballots rank the elements.
    pub fn ballots(&self) -> bool {
        self.rows > 0
    }
}

// A digit's count in a tile fits the 16 bits either scatter gives it.
const _: () = assert!(WORKGROUP * SORT_ITEMS < 1 << 16 && WORKGROUP * BALLOT_ITEMS < 1 << 16);
// The ballot-ranked scatter gives each of its threads one digit.
const _: () = assert!(WORKGROUP == 1 << BALLOT_DIGIT_BITS);

/// A sort's scratch buffer of the other side of its keys' ping-pong.
pub const KEYS: usize = 0;
/// A sort's scratch buffer of the other side of its values' ping-pong.
pub const VALUES: usize = 1;
/// A sort's scratch buffer of its tiles' digit histograms.
pub const HISTOGRAMS: usize = 2;
/// A sort's first scratch buffer of the histograms' partial sums; the other levels follow.
pub const PARTIALS: usize = 3;

/// Words of each scratch buffer an operator of `kind` over `n` elements needs, numbered as
/// [`crate::resolve::BufferRef::Scratch`]: a scan's levels of partial sums; a sort's keys and
/// values (the other side of the ping-pong; none without values), the digit histograms of its
/// tiles, and the levels of their scan. Scans run in tiles of `scan_tile` elements; sorts in
/// the `sort` shape.
pub fn scratch_words<R>(kind: &OpKind<R>, n: u64, scan_tile: u64, sort: SortShape) -> Vec<u64> {
    match kind {
        OpKind::Scan { .. } => scan_levels(n, scan_tile),
        OpKind::Sort { values, .. } => {
            let histograms = sort.radix() * n.div_ceil(sort.tile());
            let moved = if values.is_some() { n } else { 0 };
            let mut out = vec![n, moved, histograms];
            out.extend(scan_levels(histograms, scan_tile));
            out
        }
        _ => Vec::new(),
    }
}

/// What scratch buffer `index` of an operator of `kind` holds, for reports.
pub fn scratch_name<R>(kind: &OpKind<R>, index: usize) -> String {
    match (kind, index) {
        (OpKind::Sort { .. }, KEYS) => "sort keys".to_string(),
        (OpKind::Sort { .. }, VALUES) => "sort values".to_string(),
        (OpKind::Sort { .. }, HISTOGRAMS) => "sort digit histograms".to_string(),
        (OpKind::Sort { .. }, l) => format!("sort histogram partials {}", l - PARTIALS + 1),
        _ => format!("scan partials {}", index + 1),
    }
}

/// Sizes of the levels of partial sums a scan of `n` elements in tiles of `tile` needs: one
/// sum per tile, again while more than one tile remains.
fn scan_levels(n: u64, tile: u64) -> Vec<u64> {
    let mut out = Vec::new();
    let mut n = n;
    while n > tile {
        n = n.div_ceil(tile);
        out.push(n);
    }
    out
}
