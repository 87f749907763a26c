//! The operators' scratch buffers and the tiles that size them: a scan's levels of partial
//! sums; a radix sort's other keys and values, its tiles' digit histograms and their partial
//! sums. Resolve sizes them and reports name them; the operator kernels ([`crate::scan`],
//! [`crate::radix`]) number them the same way.

use crate::limits::WORKGROUP;
use crate::operator::OpKind;

/// Bits of a digit, sorted by one pass (the scatter packs the counts of the 16 digits into
/// two vectors of four words).
pub const DIGIT_BITS: u32 = 4;
/// Digits of a pass.
pub const RADIX: u64 = 1 << DIGIT_BITS;
/// Elements each thread of a sort pass ranks.
pub const SORT_ITEMS: u32 = 8;
/// Elements of a sort tile: one workgroup ranks them together.
pub const SORT_TILE: u64 = (WORKGROUP * SORT_ITEMS) as u64;
// A digit's count in a tile fits the 16 bits the scatter gives it.
const _: () = assert!(SORT_TILE < 1 << 16);

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
/// values (the other side of the ping-pong), the digit histograms of its tiles, and the levels
/// of their scan. Scans run in tiles of `scan_tile` elements.
pub fn scratch_words(kind: &OpKind, n: u64, scan_tile: u64) -> Vec<u64> {
    match kind {
        OpKind::Scan { .. } => scan_levels(n, scan_tile),
        OpKind::Sort { .. } => {
            let histograms = RADIX * n.div_ceil(SORT_TILE);
            let mut out = vec![n, n, histograms];
            out.extend(scan_levels(histograms, scan_tile));
            out
        }
        _ => Vec::new(),
    }
}

/// What scratch buffer `index` of an operator of `kind` holds, for reports.
pub fn scratch_name(kind: &OpKind, index: usize) -> String {
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
