//! Packs the billboard textures of one cloud into a single atlas (improved-billboard-cloud
//! §4 item 5: "one atlas with a greedy packing algorithm", padding around each texture;
//! animated-billboard-clouds §2.4 \[ENG\]: an atlas per cloud).
//!
//! The packing itself is the `crunch` crate's greedy best-area-fit packer (largest items
//! first, free space tracked as overlapping maximal rectangles). This module adds the
//! padding, searches for a small atlas and fixes the dimension rule: **atlas width and
//! height are multiples of 4** (block-compression friendly, e.g. BC/ETC/ASTC 4x4 or
//! KTX2 Basis), not necessarily powers of two.

use crunch::{Item, Packer, Rect, Rotation};

/// Where each texture went: the atlas size and, per input size, the top-left texel of the
/// texture itself (its padding ring lies just outside it).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Packing {
    /// Atlas width in texels, a multiple of 4.
    pub width: u32,
    /// Atlas height in texels, a multiple of 4.
    pub height: u32,
    /// Per input size, in input order: top-left texel (x right, y down) of the texture.
    pub origins: Vec<(u32, u32)>,
}

/// Packs textures of the given `(width, height)` sizes into one atlas no larger than
/// `max_size` x `max_size`, each surrounded by `padding` texels that belong to it alone
/// (so two textures are at least `2 * padding` apart and every padding ring lies inside the
/// atlas). Returns `None` when they do not fit.
///
/// The result is deterministic (it depends only on the inputs) and its dimensions are
/// multiples of 4; an empty input gives a 4 x 4 atlas. Zero sizes are treated as 1.
/// Improved-billboard-cloud §4 item 5.
pub fn pack(sizes: &[(u32, u32)], padding: u32, max_size: u32) -> Option<Packing> {
    let limit = (max_size / 4 * 4) as usize;
    if limit == 0 {
        return None;
    }
    if sizes.is_empty() {
        return Some(Packing {
            width: 4,
            height: 4,
            origins: Vec::new(),
        });
    }
    let pad = padding as usize;
    let cells: Vec<(usize, usize)> = sizes
        .iter()
        .map(|&(w, h)| {
            (
                (w.max(1) as usize).saturating_add(2 * pad),
                (h.max(1) as usize).saturating_add(2 * pad),
            )
        })
        .collect();
    let widest = cells.iter().map(|c| c.0).max().unwrap_or(1);
    let tallest = cells.iter().map(|c| c.1).max().unwrap_or(1);
    if widest > limit || tallest > limit {
        return None;
    }
    let area: u128 = cells.iter().map(|&(w, h)| (w as u128) * (h as u128)).sum();
    if area > (limit as u128) * (limit as u128) {
        return None;
    }

    if cells.len() > CRUNCH_MAX_ITEMS {
        return shelf_pack(&cells, pad, limit, widest, area);
    }
    let mut packer = Packer::with_items(
        cells
            .iter()
            .enumerate()
            .map(|(i, &(w, h))| Item::new(i, w, h, Rotation::None)),
    );
    let mut attempt = |side: usize| packer.pack(Rect::of_size(side, side)).ok();

    // A small square side (multiple of 4) that holds everything: grow 10% at a time from
    // just above the area / largest-item bound until the packer succeeds, then bisect down
    // to within 1/64 of the side (each attempt packs every item). The result is trimmed.
    let lower = ceil4(widest.max(tallest).max(isqrt_ceil(area))).min(limit) / 4;
    let (mut lo, mut hi) = (lower, (lower + lower / 20).max(lower).min(limit / 4));
    // Invariant: `best` is the packing into a square of side `hi * 4`.
    let mut best = loop {
        if let Some(items) = attempt(hi * 4) {
            break items;
        }
        if hi * 4 >= limit {
            return None;
        }
        lo = hi + 1;
        hi = (hi + hi / 10 + 1).min(limit / 4);
    };
    while hi - lo > hi / 64 {
        let mid = lo + (hi - lo) / 2;
        match attempt(mid * 4) {
            Some(items) => {
                best = items;
                hi = mid;
            }
            None => lo = mid + 1,
        }
    }
    let items = best;
    let mut origins = vec![(0u32, 0u32); sizes.len()];
    let (mut right, mut bottom) = (0usize, 0usize);
    for item in &items {
        right = right.max(item.rect.right());
        bottom = bottom.max(item.rect.bottom());
        origins[item.data] = ((item.rect.x + pad) as u32, (item.rect.y + pad) as u32);
    }
    Some(Packing {
        width: ceil4(right).min(limit) as u32,
        height: ceil4(bottom).min(limit) as u32,
        origins,
    })
}

/// Above this many textures the shelf packer replaces `crunch`, whose free-rectangle
/// bookkeeping grows quadratically with the number of textures.
const CRUNCH_MAX_ITEMS: usize = 1024;

/// First-fit decreasing-height shelves for many textures: cells sorted by height (then width,
/// then index, for determinism) fill rows left to right, each into the first shelf with room.
/// The atlas width is the smallest multiple of 4 whose packing is no taller than it is wide
/// (bisection; the height shrinks as the width grows), so the atlas comes out near square.
fn shelf_pack(
    cells: &[(usize, usize)],
    pad: usize,
    limit: usize,
    widest: usize,
    area: u128,
) -> Option<Packing> {
    let mut order: Vec<usize> = (0..cells.len()).collect();
    order.sort_by(|&a, &b| {
        cells[b]
            .1
            .cmp(&cells[a].1)
            .then(cells[b].0.cmp(&cells[a].0))
            .then(a.cmp(&b))
    });
    // Packs into `width`; returns the height used and the cell origins.
    let run = |width: usize| -> (usize, Vec<(usize, usize)>) {
        // Shelves: (y, height, used width).
        let mut shelves: Vec<(usize, usize, usize)> = Vec::new();
        let mut origins = vec![(0, 0); cells.len()];
        let mut height = 0;
        for &i in &order {
            let (w, h) = cells[i];
            match shelves.iter_mut().find(|s| s.2 + w <= width) {
                Some(s) => {
                    origins[i] = (s.2, s.0);
                    s.2 += w;
                }
                None => {
                    origins[i] = (0, height);
                    shelves.push((height, h, w));
                    height += h;
                }
            }
        }
        (height, origins)
    };
    let lower = ceil4(widest.max(isqrt_ceil(area))).min(limit) / 4;
    let (mut lo, mut hi) = (lower, limit / 4);
    let (h, o) = run(hi * 4);
    if h > limit {
        return None;
    }
    let mut best = (hi * 4, h, o);
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        let (h, o) = run(mid * 4);
        if h <= mid * 4 {
            best = (mid * 4, h, o);
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    let (_, _, origins) = best;
    let (mut right, mut bottom) = (0usize, 0usize);
    for (&(x, y), &(w, h)) in origins.iter().zip(cells) {
        right = right.max(x + w);
        bottom = bottom.max(y + h);
    }
    Some(Packing {
        width: ceil4(right).min(limit) as u32,
        height: ceil4(bottom).min(limit) as u32,
        origins: origins
            .iter()
            .map(|&(x, y)| ((x + pad) as u32, (y + pad) as u32))
            .collect(),
    })
}

/// `n` rounded up to a multiple of 4.
fn ceil4(n: usize) -> usize {
    n.div_ceil(4).saturating_mul(4)
}

/// Smallest `s` with `s * s >= n` (saturating at `usize::MAX`).
fn isqrt_ceil(n: u128) -> usize {
    let mut s = (n as f64).sqrt() as u128;
    while s * s < n {
        s += 1;
    }
    while s > 0 && (s - 1) * (s - 1) >= n {
        s -= 1;
    }
    usize::try_from(s).unwrap_or(usize::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Texture rectangles plus their padding rings, checked for overlap and bounds.
    fn assert_valid(p: &Packing, sizes: &[(u32, u32)], padding: u32) {
        assert_eq!(p.origins.len(), sizes.len());
        assert_eq!(p.width % 4, 0);
        assert_eq!(p.height % 4, 0);
        let cells: Vec<[i64; 4]> = sizes
            .iter()
            .zip(&p.origins)
            .map(|(&(w, h), &(x, y))| {
                let pad = i64::from(padding);
                [
                    i64::from(x) - pad,
                    i64::from(y) - pad,
                    i64::from(x) + i64::from(w.max(1)) + pad,
                    i64::from(y) + i64::from(h.max(1)) + pad,
                ]
            })
            .collect();
        for (i, a) in cells.iter().enumerate() {
            assert!(a[0] >= 0 && a[1] >= 0, "cell {i} {a:?}");
            assert!(a[2] <= i64::from(p.width) && a[3] <= i64::from(p.height));
            for b in &cells[i + 1..] {
                let overlap = a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3];
                assert!(!overlap, "{a:?} overlaps {b:?}");
            }
        }
    }

    #[test]
    fn packs_without_overlap_and_reasonably_tight() {
        let sizes: Vec<(u32, u32)> = (0..300u32)
            .map(|i| (4 + (i * 37) % 61, 4 + (i * 53) % 47))
            .collect();
        let p = pack(&sizes, 4, 4096).expect("fits");
        assert_valid(&p, &sizes, 4);
        let used: u64 = sizes
            .iter()
            .map(|&(w, h)| u64::from(w + 8) * u64::from(h + 8))
            .sum();
        let atlas = u64::from(p.width) * u64::from(p.height);
        assert!(used as f64 / atlas as f64 > 0.75, "{used} of {atlas}");
        assert_eq!(pack(&sizes, 4, 4096), Some(p), "deterministic");
    }

    #[test]
    fn limits_and_edge_cases() {
        assert_eq!(pack(&[], 4, 64).map(|p| (p.width, p.height)), Some((4, 4)));
        assert_eq!(pack(&[(1, 1)], 0, 3), None);
        let p = pack(&[(10, 2)], 1, 64).expect("fits");
        assert_eq!((p.width, p.height, p.origins[0]), (12, 4, (1, 1)));
        // One item larger than the limit, or too much total area.
        assert_eq!(pack(&[(62, 10)], 2, 64), None);
        assert_eq!(pack(&[(30, 30); 5], 1, 64), None);
        let p = pack(&[(30, 30); 4], 1, 64).expect("exactly four fit");
        assert_eq!((p.width, p.height), (64, 64));
        assert_valid(&p, &[(30, 30); 4], 1);
        let zero = pack(&[(0, 0), (0, 5)], 0, 16).expect("fits");
        assert_valid(&zero, &[(0, 0), (0, 5)], 0);
    }

    #[test]
    fn many_textures_go_to_shelves_without_overlap() {
        let sizes: Vec<(u32, u32)> = (0..5000u32)
            .map(|i| (4 + (i * 37) % 29, 4 + (i * 53) % 23))
            .collect();
        let p = pack(&sizes, 2, 4096).expect("fits");
        assert_valid(&p, &sizes, 2);
        let used: u64 = sizes
            .iter()
            .map(|&(w, h)| u64::from(w + 4) * u64::from(h + 4))
            .sum();
        let atlas = u64::from(p.width) * u64::from(p.height);
        assert!(used as f64 / atlas as f64 > 0.8, "{used} of {atlas}");
        assert!(
            p.width.abs_diff(p.height) < p.width / 4,
            "near square: {p:?}"
        );
        assert_eq!(pack(&sizes, 2, 4096), Some(p), "deterministic");
        // Too much for a small atlas.
        assert_eq!(pack(&sizes, 2, 256), None);
    }

    #[test]
    fn one_wide_item_gives_a_flat_atlas() {
        let p = pack(&[(1000, 12)], 4, 4096).expect("fits");
        assert_eq!((p.width, p.height), (1008, 20));
    }
}
