//! The BVH of a frame whose primary rays are rasterized: a binary linear
//! BVH (LBVH; Lauterbach et al. 2009, "Fast BVH Construction on GPUs"),
//! built in a few milliseconds for the shadow rays and probes such a frame
//! traces.
//!
//! A frame that rasterizes its primary rays traces a few rays per pixel at
//! most, so the build, not the traversal, dominates the structure's cost:
//! the tree is therefore built by sorting the primitives along a Morton
//! curve of their box centres (10 bits per axis) and splitting every range
//! where the highest bit of its codes changes (a spatial median, as Karras
//! 2012 derives the same hierarchy in parallel), halving ranges whose codes
//! are equal. Both halves of a split are built in parallel (rayon), each
//! into its own part of the node array: a range of `m` primitives owns
//! `2m − 1` slots in pre-order (its root, then its left range's slots, then
//! its right's), so no two tasks touch the same node and the layout does not
//! depend on the thread count.
//!
//! Boxes and rays are in the f32 BVH space of [`super::bvh`], which pads
//! every box and clips every ray so that a box test never hides a hit (see
//! there); the traversal tests each box with `obvhs`'s slab test from
//! distance 0 on.

use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::ray::Ray as Ray32;
use rayon::prelude::*;

/// The most primitives in a leaf.
const LEAF_SIZE: usize = 4;

/// Ranges of fewer primitives are built on the calling thread: below this,
/// splitting the work costs more than it saves.
const PARALLEL_FROM: usize = 4096;

/// Bits of a Morton code per axis: 30 bits in all, the high half of a sort
/// key whose low half is the primitive's index.
const MORTON_BITS: u32 = 10;

/// The deepest a tree gets: [`MORTON_BITS`] levels per axis of splits on
/// code bits, then at most 32 levels of halving equal codes.
const MAX_DEPTH: usize = 3 * MORTON_BITS as usize + 32;

#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Aabb,
    /// A leaf: its first primitive in leaf order; an inner node: the index
    /// of its right child (its left child is the next node).
    index: u32,
    /// A leaf: its primitives (at least one); an inner node: 0.
    count: u32,
}

/// A [`Node`] as stored: the bits of its box's `min` and `max`, then
/// `index` and `count`. Half the size of a [`Node`] (whose `Vec3A`s are
/// padded), and a slot of zeros is what a fresh zeroed allocation holds, so
/// the slots a tree leaves unused cost no writes.
type Slot = [u32; 8];

impl Node {
    fn store(&self) -> Slot {
        let [x0, y0, z0] = self.bounds.min.to_array().map(f32::to_bits);
        let [x1, y1, z1] = self.bounds.max.to_array().map(f32::to_bits);
        [x0, y0, z0, x1, y1, z1, self.index, self.count]
    }

    #[inline]
    fn load(slot: &Slot) -> Self {
        let point = |i: usize| {
            Vec3A::new(
                f32::from_bits(slot[i]),
                f32::from_bits(slot[i + 1]),
                f32::from_bits(slot[i + 2]),
            )
        };
        Self {
            bounds: Aabb::new(point(0), point(3)),
            index: slot[6],
            count: slot[7],
        }
    }
}

/// A binary BVH over boxes in BVH space.
pub struct Lbvh {
    nodes: Vec<Slot>,
    /// `order[i]`: the index in the input boxes of the `i`-th leaf
    /// primitive.
    order: Vec<u32>,
}

impl Lbvh {
    /// Builds the tree over `boxes` (not empty, fewer than 2^32).
    pub fn build(boxes: &[Aabb]) -> Self {
        assert!(!boxes.is_empty() && boxes.len() < u32::MAX as usize);
        let centres = boxes
            .par_iter()
            .map(|b| Aabb::from_point(b.center()))
            .reduce(|| Aabb::INVALID, |a, b| a.union(&b));
        let cells = (1u32 << MORTON_BITS) as f32;
        // Centres map to [0, cells); a flat axis maps to cell 0.
        let extent = centres.diagonal().max(Vec3A::splat(f32::MIN_POSITIVE));
        let to_cells = Vec3A::splat(cells) / extent;
        let mut keys: Vec<u64> = boxes
            .par_iter()
            .enumerate()
            .map(|(i, b)| {
                let cell = ((b.center() - centres.min) * to_cells)
                    .min(Vec3A::splat(cells - 1.0))
                    .max(Vec3A::ZERO);
                let code = morton(cell.x as u32, cell.y as u32, cell.z as u32);
                (u64::from(code) << 32) | i as u64
            })
            .collect();
        keys.par_sort_unstable();
        let mut nodes = vec![[0; 8]; 2 * keys.len() - 1];
        build_range(&keys, boxes, 0, &mut nodes, 0);
        let order = keys.iter().map(|&k| k as u32).collect();
        Self { nodes, order }
    }

    #[inline]
    fn node(&self, index: u32) -> Node {
        Node::load(&self.nodes[index as usize])
    }

    /// `order[i]`: the index in the input boxes of the `i`-th leaf
    /// primitive, the id the traversal reports.
    pub fn primitive_order(&self) -> &[u32] {
        &self.order
    }

    /// Offers `leaf` every primitive (in leaf order) whose box `ray` crosses
    /// within (0, `ray.tmax`), nearer boxes first; `leaf` may shorten
    /// `ray.tmax`, and stops the traversal by returning `true`.
    #[inline]
    pub fn traverse(&self, ray: &mut Ray32, mut leaf: impl FnMut(usize, &mut Ray32) -> bool) {
        if self.node(0).bounds.intersect_ray(ray) > ray.tmax {
            return;
        }
        let mut stack = [0u32; MAX_DEPTH];
        let mut depth = 0;
        let mut node = 0u32;
        loop {
            let n = self.node(node);
            if n.count > 0 {
                for prim in n.index..n.index + n.count {
                    if leaf(prim as usize, ray) {
                        return;
                    }
                }
            } else {
                let (left, right) = (node + 1, n.index);
                let t_left = self.node(left).bounds.intersect_ray(ray);
                let t_right = self.node(right).bounds.intersect_ray(ray);
                let (near, t_near, far, t_far) = if t_left <= t_right {
                    (left, t_left, right, t_right)
                } else {
                    (right, t_right, left, t_left)
                };
                if t_near <= ray.tmax {
                    if t_far <= ray.tmax {
                        stack[depth] = far;
                        depth += 1;
                    }
                    node = near;
                    continue;
                }
            }
            // The next node on the stack whose box the ray, perhaps
            // shortened since, still reaches.
            loop {
                if depth == 0 {
                    return;
                }
                depth -= 1;
                node = stack[depth];
                if self.node(node).bounds.intersect_ray(ray) <= ray.tmax {
                    break;
                }
            }
        }
    }
}

/// Builds the subtree over `keys` (sorted; their primitives start at
/// `first` in leaf order) into `nodes`, its `2·keys.len() − 1` slots, the
/// first of which is node `base`; returns its box.
fn build_range(keys: &[u64], boxes: &[Aabb], first: usize, nodes: &mut [Slot], base: u32) -> Aabb {
    let m = keys.len();
    if m <= LEAF_SIZE {
        let bounds = keys
            .iter()
            .fold(Aabb::INVALID, |a, &k| a.union(&boxes[k as u32 as usize]));
        nodes[0] = Node {
            bounds,
            index: first as u32,
            count: m as u32,
        }
        .store();
        return bounds;
    }
    let split = split_of(keys);
    let (root, rest) = nodes.split_first_mut().expect("a range owns a slot");
    let (left_nodes, right_nodes) = rest.split_at_mut(2 * split - 1);
    let right_base = base + 2 * split as u32;
    let (left_keys, right_keys) = keys.split_at(split);
    let left = |nodes: &mut [Slot]| build_range(left_keys, boxes, first, nodes, base + 1);
    let right =
        |nodes: &mut [Slot]| build_range(right_keys, boxes, first + split, nodes, right_base);
    let (left, right) = if m >= PARALLEL_FROM {
        rayon::join(|| left(left_nodes), || right(right_nodes))
    } else {
        (left(left_nodes), right(right_nodes))
    };
    let bounds = left.union(&right);
    *root = Node {
        bounds,
        index: right_base,
        count: 0,
    }
    .store();
    bounds
}

/// Where `keys` (sorted, more than one) split: before the first code whose
/// highest bit differing across the range is set; in the middle if all
/// codes are equal.
fn split_of(keys: &[u64]) -> usize {
    let code = |k: u64| k >> 32;
    let differing = code(keys[0]) ^ code(keys[keys.len() - 1]);
    if differing == 0 {
        return keys.len() / 2;
    }
    let bit = 1u64 << (63 - differing.leading_zeros());
    keys.partition_point(|&k| code(k) & bit == 0)
}

/// The Morton code of a cell (each coordinate below 2^[`MORTON_BITS`]): the
/// bits of x, y and z interleaved.
fn morton(x: u32, y: u32, z: u32) -> u32 {
    // Spreads 10 bits to every third bit (Karras 2012, "Thinking Parallel,
    // Part III").
    let spread = |v: u32| {
        let v = (v | (v << 16)) & 0x0300_00ff;
        let v = (v | (v << 8)) & 0x0300_f00f;
        let v = (v | (v << 4)) & 0x030c_30c3;
        (v | (v << 2)) & 0x0924_9249
    };
    (spread(x) << 2) | (spread(y) << 1) | spread(z)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morton_interleaves_bits() {
        // x = 0b11, y = 0b01, z = 0b10: bits (from high) x1 y1 z1 x0 y0 z0
        // = 1 0 1 1 1 0.
        assert_eq!(morton(0b11, 0b01, 0b10), 0b101110);
        assert_eq!(morton(1023, 1023, 1023), (1 << 30) - 1);
    }

    /// Every primitive sits in exactly one leaf, each node's box holds its
    /// children's, and a ray through a box's centre is offered that box.
    #[test]
    fn tree_covers_every_box() {
        let mut seed = 12345u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / (1u64 << 24) as f32
        };
        let boxes: Vec<Aabb> = (0..10_000)
            .map(|_| {
                let p = Vec3A::new(next(), next(), next()) * 100.0;
                Aabb::new(p, p + Vec3A::new(next(), next(), next()))
            })
            .collect();
        let tree = Lbvh::build(&boxes);
        let mut seen = vec![0; boxes.len()];
        for &i in tree.primitive_order() {
            seen[i as usize] += 1;
        }
        assert!(seen.iter().all(|&n| n == 1));
        fn check(tree: &Lbvh, boxes: &[Aabb], node: usize) -> Aabb {
            let n = tree.node(node as u32);
            let inner = if n.count > 0 {
                (n.index..n.index + n.count).fold(Aabb::INVALID, |a, p| {
                    a.union(&boxes[tree.primitive_order()[p as usize] as usize])
                })
            } else {
                check(tree, boxes, node + 1).union(&check(tree, boxes, n.index as usize))
            };
            assert!(n.bounds.min.cmple(inner.min).all() && n.bounds.max.cmpge(inner.max).all());
            n.bounds
        }
        check(&tree, &boxes, 0);
        for (i, b) in boxes.iter().enumerate().step_by(97) {
            let origin = b.center() + Vec3A::new(0.0, 0.0, -300.0);
            let mut ray = Ray32::new(origin, Vec3A::Z, 0.0, f32::INFINITY);
            let mut offered = false;
            tree.traverse(&mut ray, |prim, _| {
                offered |= tree.primitive_order()[prim] as usize == i;
                offered
            });
            assert!(offered, "box {i} not offered");
        }
    }
}
