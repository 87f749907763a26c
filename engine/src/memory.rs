//! Memory planning: transient buffers whose lifetimes do not overlap share memory. Each
//! transient buffer gets a range of an arena (one large GPU buffer), placed greedily, largest
//! first, at the lowest aligned offset no buffer live at the same time occupies; the other
//! buffers get memory of their own.

use std::collections::BTreeMap;

/// The frame steps (inclusive) during which a buffer holds data.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct Lifetime {
    /// First step that touches it.
    pub first: usize,
    /// Last step that touches it.
    pub last: usize,
}

impl Lifetime {
    /// Whether the two lifetimes share a step.
    pub fn overlaps(&self, other: &Lifetime) -> bool {
        self.first <= other.last && other.first <= self.last
    }
}

/// Where a buffer's bytes live.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Placement {
    /// The arena, or `None` for a buffer of its own.
    pub arena: Option<usize>,
    /// Byte offset in the arena (0 for a buffer of its own).
    pub offset: u64,
    /// Bytes.
    pub bytes: u64,
}

/// A buffer to place: its bytes, and its lifetime when it is transient.
#[derive(Debug, Clone, Copy)]
pub struct Request {
    /// Bytes.
    pub bytes: u64,
    /// `Some` for a transient buffer, which may share memory.
    pub lifetime: Option<Lifetime>,
}

/// The placement of every buffer.
#[derive(Debug, Clone)]
pub struct MemoryPlan<K: Ord> {
    /// Placement per buffer.
    pub placements: BTreeMap<K, Placement>,
    /// Size of each arena.
    pub arenas: Vec<u64>,
    /// Lifetimes of the transient buffers.
    pub lifetimes: BTreeMap<K, Lifetime>,
}

impl<K: Ord> Default for MemoryPlan<K> {
    fn default() -> Self {
        MemoryPlan {
            placements: BTreeMap::new(),
            arenas: Vec::new(),
            lifetimes: BTreeMap::new(),
        }
    }
}

impl<K: Ord + Clone> MemoryPlan<K> {
    /// Places `requests`: offsets aligned to `alignment`, arenas at most `max_arena` bytes.
    /// With `alias` false every buffer gets memory of its own.
    pub fn new(requests: &BTreeMap<K, Request>, alignment: u64, max_arena: u64, alias: bool) -> MemoryPlan<K> {
        let mut plan = MemoryPlan {
            placements: BTreeMap::new(),
            arenas: Vec::new(),
            lifetimes: BTreeMap::new(),
        };
        let mut transient: Vec<(&K, u64, Lifetime)> = Vec::new();
        for (k, r) in requests {
            match r.lifetime {
                Some(l) if alias => transient.push((k, r.bytes, l)),
                _ => {
                    plan.placements.insert(
                        k.clone(),
                        Placement {
                            arena: None,
                            offset: 0,
                            bytes: r.bytes,
                        },
                    );
                }
            }
            if let Some(l) = r.lifetime {
                plan.lifetimes.insert(k.clone(), l);
            }
        }
        // Largest first, then earliest, then by key: the same plan every time.
        transient.sort_by(|a, b| b.1.cmp(&a.1).then(a.2.cmp(&b.2)).then(a.0.cmp(b.0)));
        let mut placed: Vec<(usize, u64, u64, Lifetime)> = Vec::new();
        for (k, bytes, life) in transient {
            let (arena, offset) = Self::first_fit(&placed, &plan.arenas, bytes, life, alignment, max_arena);
            if arena == plan.arenas.len() {
                plan.arenas.push(0);
            }
            plan.arenas[arena] = plan.arenas[arena].max(offset + bytes);
            placed.push((arena, offset, bytes, life));
            plan.placements.insert(
                k.clone(),
                Placement {
                    arena: Some(arena),
                    offset,
                    bytes,
                },
            );
        }
        plan.drop_unshared_arenas();
        plan
    }

    /// Arenas in which no two buffers share bytes save nothing: their buffers get memory of
    /// their own (no alignment padding, no ranges to bind).
    fn drop_unshared_arenas(&mut self) {
        let sharing = self.sharing();
        let mut kept = Vec::new();
        for a in 0..self.arenas.len() {
            let shares = sharing.iter().any(|(x, _)| self.placements[x].arena == Some(a));
            let new = shares.then(|| {
                kept.push(self.arenas[a]);
                kept.len() - 1
            });
            for p in self.placements.values_mut().filter(|p| p.arena == Some(a)) {
                p.arena = new;
                if new.is_none() {
                    p.offset = 0;
                }
            }
        }
        self.arenas = kept;
    }

    /// The lowest aligned offset, in the first arena where it fits, at which `bytes` overlap
    /// no placed buffer live at the same time; a new arena when none has room.
    fn first_fit(
        placed: &[(usize, u64, u64, Lifetime)],
        arenas: &[u64],
        bytes: u64,
        life: Lifetime,
        alignment: u64,
        max_arena: u64,
    ) -> (usize, u64) {
        for arena in 0..arenas.len() {
            let mut busy: Vec<(u64, u64)> = placed
                .iter()
                .filter(|(a, _, _, l)| *a == arena && l.overlaps(&life))
                .map(|(_, o, b, _)| (*o, o + b))
                .collect();
            busy.sort();
            let mut offset = 0u64;
            for (start, end) in busy {
                if offset + bytes <= start {
                    break;
                }
                offset = offset.max(end.next_multiple_of(alignment));
            }
            if offset + bytes <= max_arena {
                return (arena, offset);
            }
        }
        (arenas.len(), 0)
    }

    /// Bytes of all buffers at once: the arenas plus the buffers of their own.
    pub fn peak_bytes(&self) -> u64 {
        self.arenas.iter().sum::<u64>() + self.own_bytes()
    }

    /// Bytes the same buffers would take without sharing.
    pub fn unshared_bytes(&self) -> u64 {
        self.placements.values().map(|p| p.bytes).sum()
    }

    fn own_bytes(&self) -> u64 {
        self.placements
            .values()
            .filter(|p| p.arena.is_none())
            .map(|p| p.bytes)
            .sum()
    }

    /// Pairs of buffers that share bytes of an arena.
    pub fn sharing(&self) -> Vec<(K, K)> {
        let mut out = Vec::new();
        let list: Vec<(&K, &Placement)> = self.placements.iter().filter(|(_, p)| p.arena.is_some()).collect();
        for (i, (a, pa)) in list.iter().enumerate() {
            for (b, pb) in &list[i + 1..] {
                if pa.arena == pb.arena && pa.offset < pb.offset + pb.bytes && pb.offset < pa.offset + pa.bytes {
                    out.push(((*a).clone(), (*b).clone()));
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn req(bytes: u64, life: Option<(usize, usize)>) -> Request {
        Request {
            bytes,
            lifetime: life.map(|(first, last)| Lifetime { first, last }),
        }
    }

    /// Buffers sharing memory are never live at once, and offsets are aligned.
    fn check(plan: &MemoryPlan<&'static str>, alignment: u64) {
        for (a, b) in plan.sharing() {
            let (la, lb) = (plan.lifetimes[&a], plan.lifetimes[&b]);
            assert!(
                !la.overlaps(&lb),
                "{a} {la:?} and {b} {lb:?} share memory while both live"
            );
        }
        for p in plan.placements.values() {
            assert_eq!(p.offset % alignment, 0);
        }
    }

    #[test]
    fn disjoint_lifetimes_share_and_overlapping_ones_do_not() {
        let requests: BTreeMap<&str, Request> = [
            ("a", req(1000, Some((0, 1)))),
            ("b", req(600, Some((2, 3)))),
            ("c", req(300, Some((1, 2)))),
            ("persistent", req(500, None)),
        ]
        .into_iter()
        .collect();
        let plan = MemoryPlan::new(&requests, 256, 1 << 30, true);
        check(&plan, 256);
        assert_eq!(plan.placements["b"].offset, 0, "b reuses a's memory");
        assert!(plan.placements["c"].offset >= 1000, "c overlaps a and b in time");
        assert_eq!(plan.arenas, vec![1024 + 300]);
        assert_eq!(plan.peak_bytes(), 1324 + 500);
        assert_eq!(plan.unshared_bytes(), 2400);
        let separate = MemoryPlan::new(&requests, 256, 1 << 30, false);
        assert!(separate.arenas.is_empty());
        assert_eq!(separate.peak_bytes(), 2400);
    }

    #[test]
    fn full_arenas_open_new_ones_and_arenas_sharing_nothing_go() {
        let requests: BTreeMap<&str, Request> = [
            ("a", req(800, Some((0, 0)))),
            ("b", req(800, Some((0, 0)))),
            ("c", req(800, Some((1, 1)))),
        ]
        .into_iter()
        .collect();
        let plan = MemoryPlan::new(&requests, 4, 1000, true);
        check(&plan, 4);
        // a fills arena 0, b needs a second, c reuses a's bytes; b's arena shares nothing.
        assert_eq!(plan.arenas, vec![800]);
        assert_eq!(plan.placements["b"].arena, None);
        assert_eq!(plan.placements["c"].arena, Some(0));
        assert_eq!(plan.peak_bytes(), 1600);
    }

    #[test]
    fn random_plans_never_share_live_memory() {
        let mut state = 12345u64;
        let mut next = |n: u64| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) % n
        };
        const NAMES: [&str; 12] = ["a", "b", "c", "d", "e", "f", "g", "h", "i", "j", "k", "l"];
        for _ in 0..200 {
            let requests: BTreeMap<&str, Request> = NAMES
                .iter()
                .map(|n| {
                    let first = next(6) as usize;
                    let life = (next(4) > 0).then(|| (first, first + next(3) as usize));
                    (*n, req(1 + next(5000), life))
                })
                .collect();
            let plan = MemoryPlan::new(&requests, 64, 20000, true);
            check(&plan, 64);
            assert!(plan.peak_bytes() <= plan.unshared_bytes() + 64 * NAMES.len() as u64);
        }
    }
}
