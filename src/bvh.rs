//! The bounding volume hierarchy: one tree over every sphere and triangle, built on the CPU
//! as a binary tree with a binned surface-area heuristic (subtrees in parallel), then
//! collapsed into a four-wide tree and flattened depth-first into one node buffer that
//! `shaders/trace.wgsl` and `src/cpu/trace.rs` traverse alike.
//!
//! Layout: a [`BvhNode`] holds up to four children's boxes, one lane each (the traversal
//! tests them as one four-lane slab test). Slot `k` is an interior child (`count[k] == 0`,
//! node `child[k]`), a leaf (primitives `prim_ids[child[k] .. child[k] + count[k]]`, each a
//! sphere index or a triangle index with `TRIANGLE_BIT` set: the ids of `Hit::prim`, so the
//! BVH never renumbers a primitive), or empty (`count[k] == EMPTY_SLOT`). Node 0 is the
//! root. The build is deterministic: the same scene gives the same buffer, whatever the
//! number of threads.
//!
//! Collapsing: a wide node takes its binary node's children, replacing each interior one by
//! its two children; a node left with three slots splits its largest interior slot once
//! more. So every interior slot is at least two binary levels down, the wide tree is at
//! most `MAX_DEPTH / 2` deep, and the traversal stack (three pushes a level) holds
//! [`STACK`] entries.
//!
//! Boxes are conservative: each primitive's box is widened by a relative 2^-18 of its
//! size and position before the tree is built, so the rounding of a sphere's bound and a
//! triangle test that accepts a ray a few ULP outside its triangle still find the box.

use crate::buffers::{BvhNode, EMPTY_SLOT, Sphere, TRIANGLE_BIT, Triangle};

/// Number of centroid bins per axis in the SAH sweep.
const BINS: usize = 16;
/// Most primitives a leaf is made with when the SAH prefers a leaf.
const MAX_LEAF: usize = 4;
/// Deepest a node of the binary tree may be (the root is depth 0).
pub const MAX_DEPTH: usize = 48;
/// Entries of the traversal stack (`BVH_STACK` in WGSL): at most three pushes at each
/// level of the wide tree, which is at most `MAX_DEPTH / 2` levels deep.
pub const STACK: usize = 3 * MAX_DEPTH / 2;
/// Below this many primitives a subtree is built on the current thread.
const PARALLEL_MIN: usize = 8192;
/// Relative widening of each primitive's box (see the module docs).
const PAD: f32 = 1.0 / 262_144.0;

/// The flattened tree: what the shader's `nodes` and `prim_ids` bindings hold.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bvh {
    /// Four-wide nodes, depth-first; node 0 is the root. Empty when the scene has no
    /// primitives.
    pub nodes: Vec<BvhNode>,
    /// Primitive ids in leaf order.
    pub prim_ids: Vec<u32>,
    /// Depth of the deepest wide node (the root is depth 0); `3 * depth <= STACK`.
    pub depth: usize,
}

/// A primitive as the builder sees it: its padded box, its box centre and its id.
#[derive(Clone, Copy, Debug)]
struct PrimRef {
    lo: [f32; 3],
    hi: [f32; 3],
    centre: [f32; 3],
    id: u32,
}

#[derive(Clone, Copy, Debug)]
struct Aabb {
    lo: [f32; 3],
    hi: [f32; 3],
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        lo: [f32::INFINITY; 3],
        hi: [f32::NEG_INFINITY; 3],
    };

    fn grow(&mut self, lo: [f32; 3], hi: [f32; 3]) {
        for k in 0..3 {
            self.lo[k] = self.lo[k].min(lo[k]);
            self.hi[k] = self.hi[k].max(hi[k]);
        }
    }

    /// Half the surface area (only ratios matter); 0 for an empty box.
    fn half_area(&self) -> f32 {
        let d = [0, 1, 2].map(|k| (self.hi[k] - self.lo[k]).max(0.0));
        d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
    }
}

/// A node of the tree before flattening.
enum Node {
    Leaf {
        bounds: Aabb,
        first: u32,
        count: u32,
    },
    Interior {
        bounds: Aabb,
        children: Box<(Node, Node)>,
    },
}

impl Node {
    fn bounds(&self) -> &Aabb {
        match self {
            Node::Leaf { bounds, .. } | Node::Interior { bounds, .. } => bounds,
        }
    }
}

fn padded(lo: [f32; 3], hi: [f32; 3]) -> PrimRef {
    let mut out = PrimRef {
        lo,
        hi,
        centre: [0.0; 3],
        id: 0,
    };
    let size = (0..3).fold(0.0f32, |m, k| m.max(hi[k] - lo[k]));
    for k in 0..3 {
        let pad = (size + lo[k].abs().max(hi[k].abs())) * PAD;
        out.lo[k] = lo[k] - pad;
        out.hi[k] = hi[k] + pad;
        out.centre[k] = 0.5 * out.lo[k] + 0.5 * out.hi[k];
    }
    out
}

fn sphere_ref(s: &Sphere, id: u32) -> PrimRef {
    let lo = [0, 1, 2].map(|k| s.center[k] - s.radius);
    let hi = [0, 1, 2].map(|k| s.center[k] + s.radius);
    PrimRef {
        id,
        ..padded(lo, hi)
    }
}

fn triangle_ref(t: &Triangle, id: u32) -> PrimRef {
    let lo = [0, 1, 2].map(|k| t.a[k].min(t.b[k]).min(t.c[k]));
    let hi = [0, 1, 2].map(|k| t.a[k].max(t.b[k]).max(t.c[k]));
    PrimRef {
        id,
        ..padded(lo, hi)
    }
}

impl Bvh {
    /// Builds the tree over `spheres` (ids `0..`) and `triangles` (ids `TRIANGLE_BIT | k`).
    ///
    /// Primitives with NaN coordinates get a NaN box, which no ray enters; they never panic
    /// the build.
    pub fn build(spheres: &[Sphere], triangles: &[Triangle]) -> Bvh {
        let mut refs: Vec<PrimRef> = spheres
            .iter()
            .enumerate()
            .map(|(k, s)| sphere_ref(s, k as u32))
            .chain(
                triangles
                    .iter()
                    .enumerate()
                    .map(|(k, t)| triangle_ref(t, k as u32 | TRIANGLE_BIT)),
            )
            .collect();
        if refs.is_empty() {
            return Bvh::default();
        }
        let root = build_node(&mut refs, 0, 0);
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(2 * refs.len()),
            prim_ids: refs.iter().map(|r| r.id).collect(),
            depth: 0,
        };
        flatten(&root, 0, &mut bvh);
        debug_assert!(3 * bvh.depth <= STACK);
        bvh
    }
}

/// Bounds of the boxes and of the centres of `refs`.
fn bounds_of(refs: &[PrimRef]) -> (Aabb, Aabb) {
    let mut b = Aabb::EMPTY;
    let mut c = Aabb::EMPTY;
    for r in refs {
        b.grow(r.lo, r.hi);
        c.grow(r.centre, r.centre);
    }
    (b, c)
}

/// The bin of centre coordinate `x` on an axis whose centres start at `lo` with `scale`
/// bins per unit; the same expression bins and partitions, so they agree.
fn bin_of(x: f32, lo: f32, scale: f32) -> usize {
    (((x - lo) * scale) as usize).min(BINS - 1)
}

fn build_node(refs: &mut [PrimRef], offset: usize, depth: usize) -> Node {
    let (bounds, centres) = bounds_of(refs);
    let n = refs.len();
    let leaf = Node::Leaf {
        bounds,
        first: offset as u32,
        count: n as u32,
    };
    if n == 1 || depth + 1 >= MAX_DEPTH {
        return leaf;
    }

    // Bin every centre on all three axes in one pass, then sweep each axis for the
    // cheapest split: cost = A(left)·n(left) + A(right)·n(right), relative to A(node).
    let mut bins = [[(Aabb::EMPTY, 0usize); BINS]; 3];
    let scale = [0, 1, 2].map(|k| {
        let extent = centres.hi[k] - centres.lo[k];
        if extent > 0.0 {
            BINS as f32 / extent
        } else {
            0.0
        }
    });
    for r in refs.iter() {
        for k in 0..3 {
            let b = &mut bins[k][bin_of(r.centre[k], centres.lo[k], scale[k])];
            b.0.grow(r.lo, r.hi);
            b.1 += 1;
        }
    }
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, first bin on the right)
    for k in 0..3 {
        if scale[k] <= 0.0 || !scale[k].is_finite() {
            continue;
        }
        let mut right_area = [0.0f32; BINS];
        let mut acc = Aabb::EMPTY;
        let mut right_count = [0usize; BINS];
        let mut count = 0;
        for s in (1..BINS).rev() {
            acc.grow(bins[k][s].0.lo, bins[k][s].0.hi);
            count += bins[k][s].1;
            right_area[s] = acc.half_area();
            right_count[s] = count;
        }
        let mut acc = Aabb::EMPTY;
        let mut count = 0;
        for s in 1..BINS {
            acc.grow(bins[k][s - 1].0.lo, bins[k][s - 1].0.hi);
            count += bins[k][s - 1].1;
            if count == 0 || right_count[s] == 0 {
                continue;
            }
            let cost = acc.half_area() * count as f32 + right_area[s] * right_count[s] as f32;
            if best.is_none_or(|b| cost < b.0) {
                best = Some((cost, k, s));
            }
        }
    }

    let area = bounds.half_area();
    let mid = match best {
        // A leaf costs n intersections; a split costs one more box test plus the children.
        Some((cost, _, _)) if n <= MAX_LEAF && area > 0.0 && n as f32 <= 1.0 + cost / area => {
            return leaf;
        }
        Some((_, axis, split)) => {
            let (lo, sc) = (centres.lo[axis], scale[axis]);
            let mut i = 0;
            for j in 0..n {
                if bin_of(refs[j].centre[axis], lo, sc) < split {
                    refs.swap(i, j);
                    i += 1;
                }
            }
            i
        }
        // Every centre in one place: a few primitives make a leaf, many are halved.
        None if n <= MAX_LEAF => return leaf,
        None => n / 2,
    };
    debug_assert!(mid > 0 && mid < n);

    let (left, right) = refs.split_at_mut(mid);
    let (l, r) = if n >= PARALLEL_MIN {
        rayon::join(
            || build_node(left, offset, depth + 1),
            || build_node(right, offset + mid, depth + 1),
        )
    } else {
        (
            build_node(left, offset, depth + 1),
            build_node(right, offset + mid, depth + 1),
        )
    };
    Node::Interior {
        bounds,
        children: Box::new((l, r)),
    }
}

/// The up-to-four children of a wide node made from binary node `node` (see the module
/// docs): interior children replaced by their children, then, with three slots, the
/// largest interior slot by its children. A leaf root makes a node of one slot.
fn slots_of(node: &Node) -> Vec<&Node> {
    let Node::Interior { children, .. } = node else {
        return vec![node];
    };
    let mut slots = Vec::with_capacity(4);
    for c in [&children.0, &children.1] {
        match c {
            Node::Leaf { .. } => slots.push(c),
            Node::Interior { children: g, .. } => slots.extend([&g.0, &g.1]),
        }
    }
    if slots.len() == 3 {
        let widest = (0..3)
            .filter(|&k| matches!(slots[k], Node::Interior { .. }))
            .max_by(|&a, &b| {
                let (x, y) = (slots[a].bounds().half_area(), slots[b].bounds().half_area());
                x.total_cmp(&y)
            });
        if let Some(k) = widest
            && let Node::Interior { children: g, .. } = slots[k]
        {
            slots.splice(k..=k, [&g.0, &g.1]);
        }
    }
    slots
}

/// Appends the wide node made from `node` and, depth first, the wide nodes below it;
/// returns its index.
fn flatten(node: &Node, depth: usize, bvh: &mut Bvh) -> u32 {
    bvh.depth = bvh.depth.max(depth);
    let at = bvh.nodes.len();
    bvh.nodes.push(BvhNode::default());
    let mut wide = BvhNode {
        count: [EMPTY_SLOT; 4],
        ..BvhNode::default()
    };
    for (k, slot) in slots_of(node).into_iter().enumerate() {
        let b = slot.bounds();
        wide.lo_x[k] = b.lo[0];
        wide.lo_y[k] = b.lo[1];
        wide.lo_z[k] = b.lo[2];
        wide.hi_x[k] = b.hi[0];
        wide.hi_y[k] = b.hi[1];
        wide.hi_z[k] = b.hi[2];
        (wide.child[k], wide.count[k]) = match slot {
            Node::Leaf { first, count, .. } => (*first, *count),
            Node::Interior { .. } => (flatten(slot, depth + 1, bvh), 0),
        };
    }
    bvh.nodes[at] = wide;
    at as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Triangle {
        Triangle {
            a,
            b,
            c,
            ..Triangle::default()
        }
    }

    /// Every primitive is in exactly one leaf, every node is some node's child, every
    /// slot's box holds the boxes of its node's slots, and the stack bound holds.
    fn check(bvh: &Bvh, n: usize) {
        let mut seen = vec![0u32; n];
        let mut parents = vec![0u32; bvh.nodes.len()];
        let mut ids: Vec<u32> = bvh.prim_ids.clone();
        ids.sort_unstable();
        assert_eq!(ids.len(), n);
        for node in &bvh.nodes {
            for k in 0..4 {
                let (first, count) = (node.child[k], node.count[k]);
                if count == EMPTY_SLOT {
                    continue;
                }
                if count > 0 {
                    for &id in &bvh.prim_ids[first as usize..(first + count) as usize] {
                        seen[(id & !TRIANGLE_BIT) as usize] += 1;
                    }
                    continue;
                }
                parents[first as usize] += 1;
                let c = &bvh.nodes[first as usize];
                for j in (0..4).filter(|&j| c.count[j] != EMPTY_SLOT) {
                    assert!(node.lo_x[k] <= c.lo_x[j] && c.hi_x[j] <= node.hi_x[k]);
                    assert!(node.lo_y[k] <= c.lo_y[j] && c.hi_y[j] <= node.hi_y[k]);
                    assert!(node.lo_z[k] <= c.lo_z[j] && c.hi_z[j] <= node.hi_z[k]);
                }
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
        assert_eq!(parents[0], 0);
        assert!(parents[1..].iter().all(|&p| p == 1));
        assert!(3 * bvh.depth <= STACK);
    }

    #[test]
    fn grid_of_triangles_is_a_valid_tree() {
        let mut tris = Vec::new();
        for i in 0..40 {
            for j in 0..40 {
                let (x, y) = (i as f32, j as f32);
                tris.push(tri([x, y, 0.0], [x + 1.0, y, 0.0], [x, y + 1.0, 0.0]));
            }
        }
        let bvh = Bvh::build(&[], &tris);
        check(&bvh, tris.len());
        assert!(bvh.depth < MAX_DEPTH);
    }

    #[test]
    fn coincident_primitives_are_halved_not_looped() {
        let tris = vec![tri([0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]); 1000];
        let bvh = Bvh::build(&[], &tris);
        check(&bvh, tris.len());
        assert!(bvh.depth < MAX_DEPTH);
    }

    #[test]
    fn nan_primitives_do_not_panic() {
        let tris = vec![
            tri([f32::NAN; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
            tri([0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ];
        let bvh = Bvh::build(&[], &tris);
        assert_eq!(bvh.prim_ids.len(), 2);
    }

    #[test]
    fn build_is_deterministic() {
        let tris: Vec<Triangle> = (0..20_000)
            .map(|k| {
                let x = (k as f32 * 0.618).fract() * 100.0;
                let y = (k as f32 * 0.414).fract() * 100.0;
                tri([x, y, 0.0], [x + 0.5, y, 0.1], [x, y + 0.5, 0.2])
            })
            .collect();
        let a = Bvh::build(&[], &tris);
        let b = Bvh::build(&[], &tris);
        assert_eq!(a, b);
        check(&a, tris.len());
    }
}
