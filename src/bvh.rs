//! The bounding volume hierarchy: one tree over every sphere and triangle, built on the CPU
//! with a binned surface-area heuristic (subtrees in parallel), flattened depth-first into
//! one node buffer that `shaders/trace.wgsl` and `src/cpu/trace.rs` traverse alike.
//!
//! Layout: node `k`'s first child is `k + 1`, its second child is `first`; a leaf's
//! primitives are `prim_ids[first .. first + count]`, each a sphere index or a triangle
//! index with `TRIANGLE_BIT` set (the ids of `Hit::prim`, so the BVH never renumbers a
//! primitive). The build is deterministic: the same scene gives the same buffer, whatever
//! the number of threads.
//!
//! Boxes are conservative: each primitive's box is widened by a relative 2^-18 of its
//! size and position before the tree is built, so the rounding of a sphere's bound and a
//! triangle test that accepts a ray a few ULP outside its triangle still find the box.

use crate::kernel::layout::{BvhNode, Sphere, TRIANGLE_BIT, Triangle};

/// Number of centroid bins per axis in the SAH sweep.
const BINS: usize = 16;
/// Most primitives a leaf is made with when the SAH prefers a leaf.
const MAX_LEAF: usize = 4;
/// Deepest a node may be; the traversal stack (`BVH_STACK` in WGSL) holds this many.
pub const MAX_DEPTH: usize = 48;
/// Below this many primitives a subtree is built on the current thread.
const PARALLEL_MIN: usize = 8192;
/// Relative widening of each primitive's box (see the module docs).
const PAD: f32 = 1.0 / 262_144.0;

/// The flattened tree: what the shader's `nodes` and `prim_ids` bindings hold.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bvh {
    /// Nodes, depth-first; node 0 is the root. Empty when the scene has no primitives.
    pub nodes: Vec<BvhNode>,
    /// Primitive ids in leaf order.
    pub prim_ids: Vec<u32>,
    /// Depth of the deepest leaf (the root is depth 0).
    pub depth: usize,
    /// Primitives in the largest leaf.
    pub largest_leaf: usize,
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
        axis: u32,
        children: Box<(Node, Node)>,
    },
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
            nodes: Vec::new(),
            prim_ids: refs.iter().map(|r| r.id).collect(),
            depth: 0,
            largest_leaf: 0,
        };
        // The references are done with before the flat tree is written: not both at once.
        drop(refs);
        flatten(&root, 0, &mut bvh);
        bvh.nodes.shrink_to_fit();
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
    if n > MAX_LEAF && !depth_budget_allows_sah(depth, n) {
        return median_split(refs, offset, depth, bounds, &centres);
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
    let (axis, mid) = match best {
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
            (axis, i)
        }
        // Every centre in one place: a few primitives make a leaf, many are halved.
        None if n <= MAX_LEAF => return leaf,
        None => (0, n / 2),
    };
    debug_assert!(mid > 0 && mid < n);

    interior(refs, offset, depth, bounds, axis, mid)
}

/// The interior node whose children are `refs[..mid]` and `refs[mid..]`, built in parallel
/// when the node is large.
fn interior(
    refs: &mut [PrimRef],
    offset: usize,
    depth: usize,
    bounds: Aabb,
    axis: usize,
    mid: usize,
) -> Node {
    let n = refs.len();
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
        axis: axis as u32,
        children: Box::new((l, r)),
    }
}

/// Whether a node at `depth` with `n` primitives may still split by the SAH: it may while
/// the depth left exceeds, by a margin of 4, the levels that halving would need to bring `n`
/// down to leaves of `MAX_LEAF`. Past that, the SAH's splits may peel off a few primitives
/// a level (nested "Russian doll" meshes do) and leave a leaf of thousands at the depth
/// cap, so the node is split at the object median instead: every level halves the count,
/// and no leaf exceeds `MAX_LEAF`. Trees of ordinary meshes never reach the margin.
fn depth_budget_allows_sah(depth: usize, n: usize) -> bool {
    let halvings = (n.div_ceil(MAX_LEAF) as f64).log2().ceil() as usize;
    MAX_DEPTH - 1 - depth > halvings + 4
}

/// Splits at the object median along the widest axis of the centres (the count halves),
/// ties broken by primitive id so the tree stays deterministic.
fn median_split(
    refs: &mut [PrimRef],
    offset: usize,
    depth: usize,
    bounds: Aabb,
    centres: &Aabb,
) -> Node {
    let n = refs.len();
    let extent = [0, 1, 2].map(|k| centres.hi[k] - centres.lo[k]);
    let axis = (0..3)
        .max_by(|&a, &b| {
            extent[a]
                .partial_cmp(&extent[b])
                .unwrap_or(std::cmp::Ordering::Equal)
        })
        .unwrap_or(0);
    let mid = n / 2;
    refs.select_nth_unstable_by(mid, |a, b| {
        a.centre[axis]
            .total_cmp(&b.centre[axis])
            .then(a.id.cmp(&b.id))
    });
    interior(refs, offset, depth, bounds, axis, mid)
}

fn flatten(node: &Node, depth: usize, bvh: &mut Bvh) {
    bvh.depth = bvh.depth.max(depth);
    match node {
        Node::Leaf {
            bounds,
            first,
            count,
        } => {
            bvh.largest_leaf = bvh.largest_leaf.max(*count as usize);
            bvh.nodes.push(BvhNode {
                lo: bounds.lo,
                first: *first,
                hi: bounds.hi,
                count_axis: count << 2,
            })
        }
        Node::Interior {
            bounds,
            axis,
            children,
        } => {
            let at = bvh.nodes.len();
            bvh.nodes.push(BvhNode {
                lo: bounds.lo,
                first: 0,
                hi: bounds.hi,
                count_axis: *axis,
            });
            flatten(&children.0, depth + 1, bvh);
            bvh.nodes[at].first = bvh.nodes.len() as u32;
            flatten(&children.1, depth + 1, bvh);
        }
    }
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

    /// Every primitive is in exactly one leaf, and every node's box holds its children.
    fn check(bvh: &Bvh, n: usize) {
        let mut seen = vec![0u32; n];
        let mut ids: Vec<u32> = bvh.prim_ids.clone();
        ids.sort_unstable();
        assert_eq!(ids.len(), n);
        for (k, node) in bvh.nodes.iter().enumerate() {
            let count = node.count_axis >> 2;
            if count > 0 {
                for &id in &bvh.prim_ids[node.first as usize..(node.first + count) as usize] {
                    seen[(id & !TRIANGLE_BIT) as usize] += 1;
                }
            } else {
                for child in [k + 1, node.first as usize] {
                    let c = &bvh.nodes[child];
                    for a in 0..3 {
                        assert!(node.lo[a] <= c.lo[a] && c.hi[a] <= node.hi[a]);
                    }
                }
            }
        }
        assert!(seen.iter().all(|&s| s == 1));
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
        eprintln!("DEBUG depth {} largest {}", bvh.depth, bvh.largest_leaf);
        check(&bvh, tris.len());
        assert!(bvh.depth < MAX_DEPTH);
    }

    #[test]
    fn coincident_primitives_are_halved_not_looped() {
        let tris = vec![tri([0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]); 1000];
        let bvh = Bvh::build(&[], &tris);
        eprintln!("DEBUG depth {} largest {}", bvh.depth, bvh.largest_leaf);
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
    fn deep_subtrees_still_end_in_small_leaves() {
        // Wherever the SAH has peeled its way down to (nested "Russian doll" meshes peel a
        // few primitives a level), the rule switches to median splits while the depth left
        // still holds the halvings: 10,000 scattered triangles entering at depth 34 (13
        // levels left, 12 halvings needed) end in leaves of at most MAX_LEAF.
        let (depth, largest) = subtree_at(34);
        assert!(depth < MAX_DEPTH, "depth {depth}");
        assert!(
            largest <= MAX_LEAF,
            "a leaf of {largest} primitives at depth {depth}"
        );
        // The twin: entering at depth 40, too deep for any rule, the leaf check sees the
        // leaves of 70 and more that the cap forces.
        let (_, largest) = subtree_at(40);
        assert!(largest > 50, "the leaf-size check is blind: {largest}");
    }

    /// Builds 10,000 scattered triangles as a subtree whose root is at `depth`; returns the
    /// deepest leaf's depth and the largest leaf.
    fn subtree_at(depth: usize) -> (usize, usize) {
        let mut x = 12345u32;
        let mut rnd = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x as f32 / u32::MAX as f32
        };
        let tris: Vec<Triangle> = (0..10_000)
            .map(|_| {
                let c = [rnd(), rnd(), rnd()];
                tri(c, [c[0] + 1e-3, c[1], c[2]], [c[0], c[1] + 1e-3, c[2]])
            })
            .collect();
        let mut refs: Vec<PrimRef> = tris
            .iter()
            .enumerate()
            .map(|(k, t)| triangle_ref(t, k as u32 | TRIANGLE_BIT))
            .collect();
        let root = build_node(&mut refs, 0, depth);
        let mut bvh = Bvh {
            prim_ids: refs.iter().map(|r| r.id).collect(),
            ..Bvh::default()
        };
        flatten(&root, depth, &mut bvh);
        check(&bvh, tris.len());
        (bvh.depth, bvh.largest_leaf)
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
