//! An AABB tree over a fixed set of primitives (Zheng §3.6, Z7, E3): built top-down from
//! the primitives' centres, then refitted as they move ("lazy refit": the topology stays,
//! only the boxes change) and rebuilt when refitting has made it loose.

use glam::Vec3;
use rayon::prelude::*;

use crate::solver::PARALLEL_MIN_LEN;

/// An axis-aligned box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Aabb {
    /// The box that holds nothing: the identity of [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb { min: Vec3::INFINITY, max: Vec3::NEG_INFINITY };

    /// The smallest box around `points`.
    pub fn around(points: impl IntoIterator<Item = Vec3>) -> Aabb {
        points.into_iter().fold(Aabb::EMPTY, |b, p| Aabb { min: b.min.min(p), max: b.max.max(p) })
    }

    /// The smallest box holding both.
    pub fn union(self, other: Aabb) -> Aabb {
        Aabb { min: self.min.min(other.min), max: self.max.max(other.max) }
    }

    /// This box grown by `margin` on every side.
    pub fn inflated(self, margin: f32) -> Aabb {
        Aabb { min: self.min - Vec3::splat(margin), max: self.max + Vec3::splat(margin) }
    }

    /// Whether the two boxes share a point.
    pub fn overlaps(&self, other: &Aabb) -> bool {
        !(self.min.cmpgt(other.max).any() || other.min.cmpgt(self.max).any())
    }

    /// The shortest distance between a point of this box and a point of `other`: a lower
    /// bound on the distance between anything the two hold.
    pub fn distance(&self, other: &Aabb) -> f32 {
        (self.min - other.max).max(other.min - self.max).max(Vec3::ZERO).length()
    }

    fn centre(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    fn surface_area(&self) -> f32 {
        let d = (self.max - self.min).max(Vec3::ZERO);
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }
}

/// A node: a leaf holds up to [`LEAF_SIZE`] primitives; an inner node its two children,
/// the first right after it in [`Bvh::nodes`] (the build lays the tree out depth first)
/// and the second further on, so a reverse sweep visits children before parents. 32
/// bytes: with both children and the primitive kept apart the nodes were 40, and the
/// trees of self contact the largest arrays of the contact scenes (480 bytes a particle
/// of sphere_64).
#[derive(Debug, Clone, Copy)]
struct Node {
    aabb: Aabb,
    /// The second child of an inner node; of a leaf, [`LEAF`] with its first item's place
    /// in [`Bvh::items`] and its number of items ([`Node::items`]).
    second: u32,
    /// The largest primitive index in the subtree, so that a query for primitives after
    /// a given one (each pair of a tree with itself once) skips whole subtrees.
    last: u32,
}

const _: () = assert!(std::mem::size_of::<Node>() == 32);

/// The bit of [`Node::second`] that marks a leaf: no node has the root as a child, and
/// no tree has 2³¹ nodes.
const LEAF: u32 = 1 << 31;

/// The most primitives a leaf holds. A tree of one primitive a leaf spent most of a
/// cloth's pairs with itself on its lowest levels, where every pair of nodes meets:
/// neighbouring edges of a mesh share a vertex, so their boxes always touch (on
/// fold_64_adaptive half of the 108 000 leaf pairs a listing shared a vertex). A leaf of
/// a few lists its own pairs and its pairs with another leaf directly.
const LEAF_SIZE: usize = 4;

/// Bits of a leaf's [`Node::second`] that hold its number of items.
const COUNT_BITS: u32 = 3;

const _: () = assert!(LEAF_SIZE < 1 << COUNT_BITS);

impl Node {
    /// Whether the node is a leaf ([`LEAF`]).
    fn is_leaf(&self) -> bool {
        self.second & LEAF != 0
    }

    /// The places in [`Bvh::items`] of a leaf's items, `None` for an inner node.
    fn items(&self) -> Option<std::ops::Range<usize>> {
        self.is_leaf().then(|| {
            let first = ((self.second & !LEAF) >> COUNT_BITS) as usize;
            first..first + (self.second & ((1 << COUNT_BITS) - 1)) as usize
        })
    }

    /// The children of inner node `index`.
    fn children(&self, index: u32) -> [u32; 2] {
        [index + 1, self.second]
    }
}

/// A primitive and its box, kept in its leaf's run of [`Bvh::items`].
#[derive(Debug, Clone, Copy)]
struct Item {
    aabb: Aabb,
    primitive: u32,
}

/// How much looser than at its last build a refitted tree may get, as the ratio of the
/// summed surface areas of its inner boxes, before it is rebuilt.
const REBUILD_RATIO: f32 = 2.0;

/// An AABB tree with a few primitives per leaf.
#[derive(Debug, Clone, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
    /// The primitives and their boxes, each leaf's together, leaves in the order of the
    /// nodes.
    items: Vec<Item>,
    /// Place in `items` of each primitive.
    item_of: Vec<u32>,
    /// Node of each primitive's leaf.
    leaf_of: Vec<u32>,
    /// Summed inner surface area right after the last build.
    built_cost: f32,
    /// Number of builds, for tests and statistics.
    builds: u64,
    /// The build's scratch (primitive order and centres), kept so that a rebuild over as
    /// many primitives allocates nothing.
    order: Vec<u32>,
    centres: Vec<Vec3>,
}

impl Bvh {
    /// A tree over primitives with these boxes.
    pub fn build(boxes: &[Aabb]) -> Bvh {
        let mut tree = Bvh::default();
        tree.rebuild(boxes.len(), |p| boxes[p]);
        tree
    }

    /// Builds the tree anew over `count` primitives, primitive `p` in box `boxes(p)`: each
    /// node splits its primitives at the median of their centres along the longest side
    /// of the centres' box (centres only, so coinciding primitives cannot make the split
    /// loop), down to leaves of at most [`LEAF_SIZE`].
    pub fn rebuild(&mut self, count: usize, boxes: impl Fn(usize) -> Aabb) {
        self.nodes.clear();
        self.items.clear();
        self.item_of.clear();
        self.item_of.resize(count, 0);
        self.leaf_of.clear();
        self.leaf_of.resize(count, 0);
        self.nodes.reserve_exact((2 * count.div_ceil(2)).saturating_sub(1));
        self.items.reserve_exact(count);
        let (mut order, mut centres) = (std::mem::take(&mut self.order), std::mem::take(&mut self.centres));
        order.clear();
        order.extend(0..count as u32);
        centres.clear();
        centres.extend((0..count).map(|p| boxes(p).centre()));
        if count > 0 {
            self.split(&mut order, &centres, &boxes);
        }
        (self.order, self.centres) = (order, centres);
        self.built_cost = self.inner_cost();
        self.builds += 1;
    }

    /// Adds the subtree over `primitives` and returns its node; boxes are filled in.
    fn split(&mut self, primitives: &mut [u32], centres: &[Vec3], boxes: &impl Fn(usize) -> Aabb) -> u32 {
        let index = self.nodes.len() as u32;
        if primitives.len() <= LEAF_SIZE {
            // In the order a tree of one primitive a leaf had them, so that queries visit
            // them as it did.
            order_as_leaves(primitives, centres);
            let first = self.items.len();
            for &primitive in primitives.iter() {
                self.item_of[primitive as usize] = self.items.len() as u32;
                self.leaf_of[primitive as usize] = index;
                self.items.push(Item { aabb: boxes(primitive as usize), primitive });
            }
            let items = &self.items[first..];
            let second = LEAF | (first as u32) << COUNT_BITS | items.len() as u32;
            let last = items.iter().map(|item| item.primitive).max().unwrap_or(0);
            self.nodes.push(Node { aabb: items_box(items), second, last });
            return index;
        }
        self.nodes.push(Node { aabb: Aabb::EMPTY, second: 0, last: 0 });
        let middle = halve(primitives, centres);
        let (left, right) = primitives.split_at_mut(middle);
        self.split(left, centres, boxes);
        let second = self.split(right, centres, boxes);
        let (a, b) = (self.nodes[index as usize + 1], self.nodes[second as usize]);
        self.nodes[index as usize] = Node { aabb: a.aabb.union(b.aabb), second, last: a.last.max(b.last) };
        index
    }

    /// Puts the primitives' new boxes `boxes(p)` into the leaves and recomputes every
    /// node's box, children before parents; rebuilds instead when the tree has become
    /// [`REBUILD_RATIO`] times looser than when it was built, or when the number of
    /// primitives changed to `count`. Returns whether it rebuilt. The items are where the
    /// boxes are kept ([`Bvh::aabb`]): an array of them beside the tree held every box
    /// twice.
    pub fn refit(&mut self, count: usize, boxes: impl Fn(usize) -> Aabb + Sync) -> bool {
        if count != self.leaf_of.len() {
            self.rebuild(count, boxes);
            return true;
        }
        self.items.par_iter_mut().with_min_len(PARALLEL_MIN_LEN).for_each(|item| {
            item.aabb = boxes(item.primitive as usize);
        });
        let items = &self.items;
        self.nodes.par_iter_mut().with_min_len(PARALLEL_MIN_LEN).for_each(|node| {
            if let Some(range) = node.items() {
                node.aabb = items_box(&items[range]);
            }
        });
        for index in (0..self.nodes.len()).rev() {
            let node = self.nodes[index];
            if !node.is_leaf() {
                let [a, b] = node.children(index as u32).map(|c| self.nodes[c as usize].aabb);
                self.nodes[index].aabb = a.union(b);
            }
        }
        if self.inner_cost() > REBUILD_RATIO * self.built_cost.max(f32::MIN_POSITIVE) {
            self.rebuild(count, boxes);
            return true;
        }
        false
    }

    /// Puts `aabb` into `primitive`'s item and grows every box above it to hold it, which
    /// keeps queries exact for the items and costs the tree's depth, where a refit costs
    /// every node (0.26 ms for sphere_64's two trees); the nodes' boxes only grow, until
    /// the next refit.
    pub fn enlarge(&mut self, primitive: u32, aabb: Aabb) {
        let leaf = self.leaf_of[primitive as usize];
        let mut index = 0;
        loop {
            let node = &mut self.nodes[index as usize];
            node.aabb = node.aabb.union(aabb);
            if index == leaf {
                break;
            }
            // The first child's subtree runs from right after its parent to the second.
            index = if leaf < node.second { index + 1 } else { node.second };
        }
        self.items[self.item_of[primitive as usize] as usize].aabb = aabb;
    }

    /// The summed surface areas of the inner boxes of the tree of one primitive a leaf
    /// that the build's splits make, added in its nodes' order (the same sum, to the bit,
    /// whatever the leaves hold): a leaf's items stand for the inner nodes that were
    /// above them.
    fn inner_cost(&self) -> f32 {
        let mut cost = 0.0;
        for node in &self.nodes {
            match node.items() {
                Some(items) => add_inner_cost(&self.items[items], &mut cost),
                None => cost += node.aabb.surface_area(),
            }
        }
        cost
    }

    /// Calls `visit` with every primitive whose box overlaps `query`, top-down with
    /// pruning.
    pub fn query(&self, query: &Aabb, visit: impl FnMut(u32)) {
        self.query_from(query, 0, visit);
    }

    /// Calls `visit` with every primitive numbered `first` or later whose box overlaps
    /// `query`, top-down, pruning subtrees whose boxes miss it or whose primitives all
    /// come before `first`. A node's children are tested before they are pushed; the
    /// second is visited first, and a leaf's items last to first.
    pub fn query_from(&self, query: &Aabb, first: u32, mut visit: impl FnMut(u32)) {
        let wanted = |node: &Node| node.last >= first && node.aabb.overlaps(query);
        if self.nodes.first().is_none_or(|root| !wanted(root)) {
            return;
        }
        let mut stack = [0u32; 64];
        let mut depth = 1;
        while depth > 0 {
            depth -= 1;
            let index = stack[depth];
            let node = &self.nodes[index as usize];
            if let Some(items) = node.items() {
                for item in self.items[items].iter().rev() {
                    if item.primitive >= first && item.aabb.overlaps(query) {
                        visit(item.primitive);
                    }
                }
                continue;
            }
            for child in node.children(index) {
                if wanted(&self.nodes[child as usize]) {
                    stack[depth] = child;
                    depth += 1;
                }
            }
        }
    }

    /// The box of `primitive`, as the last build, refit or enlargement gave it.
    pub fn aabb(&self, primitive: u32) -> Aabb {
        self.items[self.item_of[primitive as usize] as usize].aabb
    }

    /// Sets `roots` to the pairs of subtrees whose primitive pairs [`Bvh::overlaps_below`]
    /// lists, so that together they hold every pair of primitives with overlapping boxes
    /// once: each subtree `depth` levels down (or a leaf above that) with itself, and each
    /// two different ones whose boxes overlap. They split a tree's pairs with itself into
    /// independent parts, for threads.
    pub fn self_overlap_roots(&self, depth: u32, roots: &mut Vec<[u32; 2]>) {
        roots.clear();
        if !self.nodes.is_empty() {
            self.pairs_below(0, 0, depth, &mut |a, b| roots.push([a, b]));
        }
    }

    /// Calls `visit(p, q)`, `p < q`, for every pair of primitives under the subtree pair
    /// `root` ([`Bvh::self_overlap_roots`]) whose boxes overlap, descending both subtrees
    /// together: a pair of nodes whose boxes miss prunes every pair below them, where a
    /// query per primitive walks from the root each time (on fold_64 and sphere_64, 12 000
    /// edges a listing). The pairs of a leaf, and of two leaves, are tested item by item.
    pub fn overlaps_below(&self, root: [u32; 2], mut visit: impl FnMut(u32, u32)) {
        self.pairs_below(root[0], root[1], u32::MAX, &mut |a, b| {
            let [Some(first), Some(second)] = [a, b].map(|n| self.nodes[n as usize].items()) else {
                unreachable!("unlimited depth descends to leaves")
            };
            let mut pair = |p: &Item, q: &Item| {
                if p.aabb.overlaps(&q.aabb) {
                    visit(p.primitive.min(q.primitive), p.primitive.max(q.primitive));
                }
            };
            let (first, second) = (&self.items[first], &self.items[second]);
            if a == b {
                for (k, p) in first.iter().enumerate() {
                    first[k + 1..].iter().for_each(|q| pair(p, q));
                }
            } else {
                for p in first {
                    second.iter().for_each(|q| pair(p, q));
                }
            }
        });
    }

    /// Calls `emit(a, b)` for the node pairs under nodes `a` and `b` (`a == b`: the pairs
    /// within one subtree, each once) whose boxes overlap, `depth` levels down or at
    /// leaves. Of two different inner nodes, the one with the larger box is split.
    fn pairs_below(&self, a: u32, b: u32, depth: u32, emit: &mut impl FnMut(u32, u32)) {
        let (node_a, node_b) = (&self.nodes[a as usize], &self.nodes[b as usize]);
        if a == b {
            if node_a.is_leaf() || depth == 0 {
                emit(a, a);
            } else {
                let [left, right] = node_a.children(a);
                self.pairs_below(left, left, depth - 1, emit);
                self.pairs_below(right, right, depth - 1, emit);
                self.pairs_below(left, right, depth - 1, emit);
            }
            return;
        }
        if !node_a.aabb.overlaps(&node_b.aabb) {
            return;
        }
        let split_a = match (node_a.is_leaf(), node_b.is_leaf()) {
            (true, true) => return emit(a, b),
            _ if depth == 0 => return emit(a, b),
            (false, true) => true,
            (true, false) => false,
            (false, false) => node_a.aabb.surface_area() >= node_b.aabb.surface_area(),
        };
        match split_a {
            true => node_a.children(a).map(|child| self.pairs_below(child, b, depth - 1, emit)),
            false => node_b.children(b).map(|child| self.pairs_below(a, child, depth - 1, emit)),
        };
    }

    /// How many times the tree was built.
    pub fn builds(&self) -> u64 {
        self.builds
    }

    /// Number of primitives.
    pub fn len(&self) -> usize {
        self.leaf_of.len()
    }

    /// Whether the tree holds nothing.
    pub fn is_empty(&self) -> bool {
        self.leaf_of.is_empty()
    }
}

/// Splits `primitives` at the median of their centres along the longest side of the
/// centres' box, returning where the second half begins.
fn halve(primitives: &mut [u32], centres: &[Vec3]) -> usize {
    let spread = Aabb::around(primitives.iter().map(|&p| centres[p as usize]));
    let extent = spread.max - spread.min;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let middle = primitives.len() / 2;
    primitives.select_nth_unstable_by(middle, |&a, &b| {
        centres[a as usize][axis].total_cmp(&centres[b as usize][axis]).then(a.cmp(&b))
    });
    middle
}

/// Orders a leaf's `primitives` as a tree of one primitive a leaf would have laid them
/// out, splitting each half again.
fn order_as_leaves(primitives: &mut [u32], centres: &[Vec3]) {
    if primitives.len() > 1 {
        let middle = halve(primitives, centres);
        let (left, right) = primitives.split_at_mut(middle);
        order_as_leaves(left, centres);
        order_as_leaves(right, centres);
    }
}

/// The box around the `items`' boxes.
fn items_box(items: &[Item]) -> Aabb {
    items.iter().fold(Aabb::EMPTY, |b, item| b.union(item.aabb))
}

/// Adds to `cost` the surface areas of the boxes of the inner nodes that a tree of one
/// primitive a leaf had over `items` ([`order_as_leaves`]), in its nodes' order.
fn add_inner_cost(items: &[Item], cost: &mut f32) {
    if items.len() > 1 {
        *cost += items_box(items).surface_area();
        let (left, right) = items.split_at(items.len() / 2);
        add_inner_cost(left, cost);
        add_inner_cost(right, cost);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(at: Vec3, half: f32) -> Aabb {
        Aabb { min: at - Vec3::splat(half), max: at + Vec3::splat(half) }
    }

    fn brute_force(boxes: &[Aabb], query: &Aabb) -> Vec<u32> {
        (0..boxes.len() as u32).filter(|&i| boxes[i as usize].overlaps(query)).collect()
    }

    fn found(tree: &Bvh, query: &Aabb) -> Vec<u32> {
        let mut hits = Vec::new();
        tree.query(query, |p| hits.push(p));
        hits.sort_unstable();
        hits
    }

    /// A scattered, deterministic cloud of small boxes.
    fn cloud(n: usize, shift: f32) -> Vec<Aabb> {
        (0..n)
            .map(|i| {
                let s = i as f32;
                cube(Vec3::new((s * 0.618).fract(), (s * 0.414).fract() + shift * s.sin(), (s * 0.732).fract()), 0.02)
            })
            .collect()
    }

    #[test]
    fn queries_find_exactly_the_overlapping_boxes_after_build_and_refit() {
        let boxes = cloud(500, 0.0);
        let mut tree = Bvh::build(&boxes);
        let queries: Vec<Aabb> = (0..40).map(|k| cube(Vec3::splat(k as f32 / 40.0), 0.05)).collect();
        for q in &queries {
            assert_eq!(found(&tree, q), brute_force(&boxes, q));
        }
        let moved = cloud(500, 0.01);
        assert!(!tree.refit(moved.len(), |p| moved[p]), "a small motion refits without rebuilding");
        for q in &queries {
            assert_eq!(found(&tree, q), brute_force(&moved, q));
        }
        assert_eq!(tree.builds(), 1);
    }

    #[test]
    fn queries_find_exactly_the_overlapping_boxes_after_some_are_enlarged_in_place() {
        let mut boxes = cloud(500, 0.0);
        let mut tree = Bvh::build(&boxes);
        for p in [3, 77, 250, 499] {
            boxes[p] = cube(boxes[p].centre() + Vec3::new(0.3, -0.2, 0.1), 0.03);
            tree.enlarge(p as u32, boxes[p]);
            assert_eq!(tree.aabb(p as u32), boxes[p]);
        }
        for k in 0..40 {
            let q = cube(Vec3::splat(k as f32 / 40.0), 0.05);
            assert_eq!(found(&tree, &q), brute_force(&boxes, &q), "query {k}");
        }
        for (p, b) in boxes.iter().enumerate() {
            assert!(found(&tree, b).contains(&(p as u32)), "each box finds itself");
        }
    }

    #[test]
    fn the_distance_between_boxes_is_that_of_their_nearest_points() {
        let unit = cube(Vec3::ZERO, 0.5);
        assert_eq!(unit.distance(&cube(Vec3::new(0.7, 0.2, 0.0), 0.5)), 0.0);
        assert_eq!(unit.distance(&cube(Vec3::new(0.0, -3.0, 0.0), 0.5)), 2.0);
        let corner = cube(Vec3::new(4.0, 5.0, -1.0), 0.5);
        assert_eq!(unit.distance(&corner), Vec3::new(3.0, 4.0, 0.0).length());
        assert_eq!(corner.distance(&unit), unit.distance(&corner));
    }

    #[test]
    fn a_query_from_a_primitive_finds_exactly_the_later_overlapping_ones() {
        let boxes = cloud(500, 0.0);
        let tree = Bvh::build(&boxes);
        for (k, query) in boxes.iter().enumerate().step_by(7) {
            let first = k as u32 + 1;
            let mut hits = Vec::new();
            tree.query_from(query, first, |p| hits.push(p));
            hits.sort_unstable();
            let expected: Vec<u32> = brute_force(&boxes, query).into_iter().filter(|&p| p >= first).collect();
            assert_eq!(hits, expected);
        }
    }

    #[test]
    fn the_subtree_pairs_list_every_overlapping_pair_of_primitives_once() {
        let boxes: Vec<Aabb> = cloud(700, 0.0).iter().map(|b| b.inflated(0.03)).collect();
        let tree = Bvh::build(&boxes);
        let mut expected = Vec::new();
        for (p, a) in boxes.iter().enumerate() {
            for (q, b) in boxes.iter().enumerate().skip(p + 1) {
                if a.overlaps(b) {
                    expected.push([p as u32, q as u32]);
                }
            }
        }
        assert!(expected.len() > 100, "the cloud has overlaps to find ({})", expected.len());
        for depth in [0, 1, 4, 30] {
            let mut roots = Vec::new();
            tree.self_overlap_roots(depth, &mut roots);
            let mut found = Vec::new();
            for &root in &roots {
                tree.overlaps_below(root, |p, q| found.push([p, q]));
            }
            found.sort_unstable();
            assert_eq!(found, expected, "subtrees {depth} levels down");
        }
    }

    /// The summed inner areas of the tree of one primitive a leaf over `boxes`, its nodes
    /// in depth-first order, as [`Bvh::refit`] measures looseness against.
    fn single_leaf_cost(primitives: &mut [u32], centres: &[Vec3], boxes: &[Aabb], cost: &mut f32) {
        if primitives.len() > 1 {
            *cost += primitives.iter().fold(Aabb::EMPTY, |b, &p| b.union(boxes[p as usize])).surface_area();
            let middle = halve(primitives, centres);
            let (left, right) = primitives.split_at_mut(middle);
            single_leaf_cost(left, centres, boxes, cost);
            single_leaf_cost(right, centres, boxes, cost);
        }
    }

    #[test]
    fn leaves_of_several_primitives_keep_the_looseness_and_query_order_of_single_ones() {
        let boxes = cloud(333, 0.0);
        let moved = cloud(333, 0.01);
        let mut tree = Bvh::build(&boxes);
        assert!(tree.nodes.len() < boxes.len(), "{} nodes", tree.nodes.len());
        let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
        let centres: Vec<Vec3> = boxes.iter().map(Aabb::centre).collect();
        let mut expected = 0.0;
        single_leaf_cost(&mut order, &centres, &boxes, &mut expected);
        assert_eq!(tree.built_cost.to_bits(), expected.to_bits());
        tree.refit(moved.len(), |p| moved[p]);
        let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
        let mut refitted = 0.0;
        single_leaf_cost(&mut order, &centres, &moved, &mut refitted);
        assert_eq!(tree.inner_cost().to_bits(), refitted.to_bits());
        // A query that meets every box visits the leaves of one primitive depth first,
        // the second child first: the build's order reversed.
        let mut visited = Vec::new();
        tree.query(&cube(Vec3::splat(0.5), 10.0), |p| visited.push(p));
        order.reverse();
        assert_eq!(visited, order);
    }

    #[test]
    fn a_tree_loosened_by_large_motion_is_rebuilt() {
        let boxes = cloud(300, 0.0);
        let mut tree = Bvh::build(&boxes);
        // Shuffle the primitives far apart: neighbours in the tree are no longer close.
        let scrambled: Vec<Aabb> = boxes
            .iter()
            .enumerate()
            .map(|(i, b)| cube(b.centre() * 0.1 + Vec3::splat(((i * 7919) % 300) as f32 / 30.0), 0.02))
            .collect();
        assert!(tree.refit(scrambled.len(), |p| scrambled[p]));
        assert_eq!(tree.builds(), 2);
        let q = cube(Vec3::splat(5.0), 0.5);
        assert_eq!(found(&tree, &q), brute_force(&scrambled, &q));
    }
}
