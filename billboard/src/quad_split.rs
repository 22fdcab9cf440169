//! Compact quads: a plane's leaves split into groups whose quads cover less empty area
//! (spec improved-billboard-cloud §4, "minimal quads"). The plane search gathers every leaf
//! within ε of a plane, wherever it lies on it, so one plane's quad can span the crown with most
//! of its area empty. Empty texels still cost atlas memory and overdraw; where the LOD's
//! triangle budget has room, a second quad over part of the leaves is cheaper than the empty
//! area between them. A split never drops a leaf: every triangle of the group lands on exactly
//! one of its two halves.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use glam::{Vec2, Vec3};

use crate::cloud::fit_quad;
use crate::{Plane, Quad, TriangleSoup};

/// A split is made only when the two halves' boxes together cover at most this fraction of
/// the quad they replace: a smaller saving is not worth a quad (two triangles, a cell of
/// atlas padding) and would cut leaf clumps that belong together. One cut through evenly
/// scattered leaves saves about a third, and the cuts after it more, so the bar is low.
pub const MAX_SPLIT_AREA_FRACTION: f32 = 0.9;

/// One quad's leaves: the triangles it replaces and those drawn on it (a superset with the
/// increased-density option), on one plane.
#[derive(Clone, Debug, PartialEq)]
pub struct QuadGroup {
    /// The plane the leaves lie near.
    pub plane: Plane,
    /// The minimal quad of `own` on `plane`.
    pub quad: Quad,
    /// Triangles (soup indices) the quad replaces.
    pub own: Vec<usize>,
    /// Triangles drawn onto the quad's texture.
    pub drawn: Vec<usize>,
    /// Index of the group it came from in [`split_quads`]' input (its own, before any split).
    pub source: usize,
}

impl QuadGroup {
    /// The group of `own` on `plane`, drawing `drawn`.
    pub fn new(
        soup: &TriangleSoup,
        plane: Plane,
        own: Vec<usize>,
        drawn: Vec<usize>,
        source: usize,
    ) -> Self {
        let quad = fit_quad(soup, &plane, &own);
        QuadGroup {
            plane,
            quad,
            own,
            drawn,
            source,
        }
    }
}

/// Splits the groups, largest saving of quad area first, until there are `max_quads` of them
/// or no split saves enough ([`MAX_SPLIT_AREA_FRACTION`]). Each split cuts a group's leaves in
/// two along the longer side of its quad, where the two halves' boxes are smallest. The result
/// keeps the input's order, a split group's halves in its place; the same input gives the same
/// output.
pub fn split_quads(
    soup: &TriangleSoup,
    groups: Vec<QuadGroup>,
    max_quads: usize,
) -> Vec<QuadGroup> {
    // Slots hold the groups in order; a split group's slot holds its halves' slots.
    let mut slots: Vec<Slot> = Vec::with_capacity(groups.len());
    let mut heap = BinaryHeap::new();
    let inputs = groups.len();
    for (source, mut g) in groups.into_iter().enumerate() {
        g.source = source;
        let id = slots.len();
        if let Some(c) = candidate(soup, &g, id) {
            heap.push(c);
        }
        slots.push(Slot::Leaf(g));
    }
    let mut count = slots.len();
    while count < max_quads {
        let Some(best) = heap.pop() else { break };
        let Slot::Leaf(group) = std::mem::replace(&mut slots[best.slot], Slot::Split(0, 0)) else {
            continue;
        };
        let halves = best.halves.map(|own| {
            let drawn = drawn_within(soup, &group, &own);
            QuadGroup::new(soup, group.plane, own, drawn, group.source)
        });
        let [a, b] = halves;
        let (ia, ib) = (slots.len(), slots.len() + 1);
        for (id, g) in [(ia, &a), (ib, &b)] {
            if let Some(c) = candidate(soup, g, id) {
                heap.push(c);
            }
        }
        slots.push(Slot::Leaf(a));
        slots.push(Slot::Leaf(b));
        slots[best.slot] = Slot::Split(ia, ib);
        count += 1;
    }
    let mut out = Vec::with_capacity(count);
    flatten(&mut slots, &(0..inputs).collect::<Vec<_>>(), &mut out);
    out
}

/// A group, or the slots of the halves it was split into.
enum Slot {
    Leaf(QuadGroup),
    Split(usize, usize),
}

/// Appends the groups of `ids` in order, each split slot replaced by its halves.
fn flatten(slots: &mut [Slot], ids: &[usize], out: &mut Vec<QuadGroup>) {
    for &id in ids {
        match std::mem::replace(&mut slots[id], Slot::Split(0, 0)) {
            Slot::Leaf(g) => out.push(g),
            Slot::Split(a, b) if a != b => flatten(slots, &[a, b], out),
            Slot::Split(..) => {}
        }
    }
}

/// A group's best split and what it saves.
struct Candidate {
    /// Quad area saved (world units²).
    saving: f32,
    slot: usize,
    halves: [Vec<usize>; 2],
}

impl PartialEq for Candidate {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Candidate {}
impl PartialOrd for Candidate {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Candidate {
    /// Largest saving first; the earlier slot on a tie (a deterministic order).
    fn cmp(&self, other: &Self) -> Ordering {
        self.saving
            .total_cmp(&other.saving)
            .then(other.slot.cmp(&self.slot))
    }
}

/// The best split of `g` (slot `slot`), if it saves enough.
fn candidate(soup: &TriangleSoup, g: &QuadGroup, slot: usize) -> Option<Candidate> {
    if g.own.len() < 2 {
        return None;
    }
    let area = 4.0 * g.quad.half_size.x * g.quad.half_size.y;
    if area <= 0.0 {
        return None;
    }
    let (u, v) = (g.quad.axis_u, g.quad.axis_v);
    let boxes: Vec<Box2> = g
        .own
        .iter()
        .map(|&t| Box2::of(soup.positions[t].map(|p| in_plane(p, u, v))))
        .collect();
    // Along the quad's longer side first: on a tie that one wins.
    let axes = if g.quad.half_size.x >= g.quad.half_size.y {
        [0, 1]
    } else {
        [1, 0]
    };
    let mut best: Option<(f32, usize, Vec<usize>)> = None;
    for axis in axes {
        let mut order: Vec<usize> = (0..g.own.len()).collect();
        order.sort_by(|&a, &b| {
            boxes[a].centre()[axis]
                .total_cmp(&boxes[b].centre()[axis])
                .then(g.own[a].cmp(&g.own[b]))
        });
        let (at, split_area) = best_cut(&order, &boxes);
        if best.as_ref().is_none_or(|b| split_area < b.0) {
            best = Some((split_area, at, order));
        }
    }
    let (split_area, at, order) = best?;
    if split_area > MAX_SPLIT_AREA_FRACTION * area {
        return None;
    }
    let mut a: Vec<usize> = order[..at].iter().map(|&i| g.own[i]).collect();
    let mut b: Vec<usize> = order[at..].iter().map(|&i| g.own[i]).collect();
    a.sort_unstable();
    b.sort_unstable();
    Some(Candidate {
        saving: area - split_area,
        slot,
        halves: [a, b],
    })
}

/// The cut of `order` (indices into `boxes`, sorted along an axis) whose two halves' boxes
/// have the least total area: the first index of the second half and that area.
fn best_cut(order: &[usize], boxes: &[Box2]) -> (usize, f32) {
    let n = order.len();
    let mut suffix = vec![Box2::EMPTY; n + 1];
    for i in (0..n).rev() {
        suffix[i] = suffix[i + 1].union(boxes[order[i]]);
    }
    let mut prefix = Box2::EMPTY;
    let mut best = (n, f32::INFINITY);
    for i in 1..n {
        prefix = prefix.union(boxes[order[i - 1]]);
        let a = prefix.area() + suffix[i].area();
        if a < best.1 {
            best = (i, a);
        }
    }
    best
}

/// The triangles of `group.drawn` whose centre lies in the box of the half `own` (and `own`
/// itself): what is drawn on the half's quad.
fn drawn_within(soup: &TriangleSoup, group: &QuadGroup, own: &[usize]) -> Vec<usize> {
    if group.drawn == group.own {
        return own.to_vec();
    }
    let (u, v) = (group.quad.axis_u, group.quad.axis_v);
    let area = own.iter().fold(Box2::EMPTY, |b, &t| {
        b.union(Box2::of(soup.positions[t].map(|p| in_plane(p, u, v))))
    });
    let mut drawn: Vec<usize> = group
        .drawn
        .iter()
        .copied()
        .filter(|&t| {
            let c = soup.positions[t].iter().copied().sum::<Vec3>() / 3.0;
            area.contains(in_plane(c, u, v))
        })
        .chain(own.iter().copied())
        .collect();
    drawn.sort_unstable();
    drawn.dedup();
    drawn
}

/// `p` in the quad's frame (any origin: only extents are compared).
fn in_plane(p: Vec3, u: Vec3, v: Vec3) -> Vec2 {
    Vec2::new(p.dot(u), p.dot(v))
}

/// An axis-aligned box in a quad's frame.
#[derive(Clone, Copy, Debug)]
struct Box2 {
    min: Vec2,
    max: Vec2,
}

impl Box2 {
    const EMPTY: Box2 = Box2 {
        min: Vec2::splat(f32::INFINITY),
        max: Vec2::splat(f32::NEG_INFINITY),
    };

    fn of(points: [Vec2; 3]) -> Box2 {
        points.iter().fold(Box2::EMPTY, |b, &p| Box2 {
            min: b.min.min(p),
            max: b.max.max(p),
        })
    }

    fn union(self, o: Box2) -> Box2 {
        Box2 {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    fn area(&self) -> f32 {
        let d = (self.max - self.min).max(Vec2::ZERO);
        d.x * d.y
    }

    fn centre(&self) -> [f32; 2] {
        let c = 0.5 * (self.min + self.max);
        [c.x, c.y]
    }

    fn contains(&self, p: Vec2) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Unit leaves (two triangles each) on the plane z = 0 at `centres`.
    fn leaves(centres: &[Vec2]) -> TriangleSoup {
        let mut positions = Vec::new();
        for c in centres {
            let p = |x: f32, y: f32| Vec3::new(c.x + x, c.y + y, 0.0);
            positions.push([p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0)]);
            positions.push([p(0.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)]);
        }
        let n = positions.len();
        TriangleSoup {
            positions,
            uvs: vec![[Vec2::ZERO; 3]; n],
            material: vec![0; n],
        }
    }

    fn plane() -> Plane {
        Plane {
            normal: Vec3::Z,
            offset: 0.0,
        }
    }

    fn one_group(soup: &TriangleSoup) -> Vec<QuadGroup> {
        let all: Vec<usize> = (0..soup.positions.len()).collect();
        vec![QuadGroup::new(soup, plane(), all.clone(), all, 0)]
    }

    fn area(groups: &[QuadGroup]) -> f32 {
        groups.iter().map(|g| g.quad.area()).sum()
    }

    fn every_triangle_once(groups: &[QuadGroup], n: usize) {
        let mut seen = vec![0; n];
        for g in groups {
            for &t in &g.own {
                seen[t] += 1;
            }
            assert!(g.own.iter().all(|t| g.drawn.contains(t)));
        }
        assert!(seen.iter().all(|&c| c == 1), "{seen:?}");
    }

    #[test]
    fn far_apart_clumps_get_a_quad_each_and_keep_every_leaf() {
        let soup = leaves(&[
            Vec2::new(0.0, 0.0),
            Vec2::new(0.8, 0.1),
            Vec2::new(20.0, 10.0),
            Vec2::new(20.7, 10.0),
        ]);
        let before = one_group(&soup);
        let after = split_quads(&soup, before.clone(), 8);
        every_triangle_once(&after, soup.positions.len());
        assert_eq!(after.len(), 2, "two clumps, each compact");
        assert!(
            area(&after) < 0.2 * area(&before),
            "{} vs {}",
            area(&after),
            area(&before)
        );
    }

    #[test]
    fn a_compact_clump_stays_one_quad_and_the_budget_holds() {
        let grid: Vec<Vec2> = (0..16)
            .map(|i| Vec2::new((i % 4) as f32, (i / 4) as f32))
            .collect();
        let soup = leaves(&grid);
        assert_eq!(split_quads(&soup, one_group(&soup), 64).len(), 1);
        let scattered: Vec<Vec2> = (0..16)
            .map(|i| Vec2::new(10.0 * (i % 4) as f32, 10.0 * (i / 4) as f32))
            .collect();
        let soup = leaves(&scattered);
        let groups = one_group(&soup);
        for budget in [1, 3, 7, 16, 40] {
            let split = split_quads(&soup, groups.clone(), budget);
            assert_eq!(split.len(), budget.clamp(1, 16), "budget {budget}");
            every_triangle_once(&split, soup.positions.len());
        }
    }

    #[test]
    fn the_order_and_split_are_the_same_every_time() {
        let centres: Vec<Vec2> = (0..40)
            .map(|i| Vec2::new((i * 37 % 23) as f32 * 3.0, (i * 11 % 17) as f32 * 2.0))
            .collect();
        let soup = leaves(&centres);
        let a = split_quads(&soup, one_group(&soup), 10);
        let b = split_quads(&soup, one_group(&soup), 10);
        assert_eq!(a, b);
    }
}
