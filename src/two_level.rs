//! The two-level BVH of a scene with `[[instances]]` (`shaders/instance.wgsl` traverses
//! it): one bottom-level tree per placed mesh, built once however often the mesh is
//! placed (and cached as any BVH), one over the scene's own primitives, and a top-level
//! tree over the instances, each of its leaves one instance.
//!
//! Layout, in one node buffer: the top-level tree from node 0, then the scene's own tree,
//! then each mesh's; the primitive ids of the bottom-level trees in one list. A bottom
//! tree's ids are the scene's own (a mesh's triangle keeps its index in
//! `SceneBuffers::triangles`), so shading reads the triangle it always read. Instance 0
//! is the scene's own primitives (the identity); a named mesh that is not hidden is drawn
//! where its entry placed it by an identity instance; then the file's `[[instances]]`.

use crate::bvh::Bvh;
use crate::scene::{Affine, IDENTITY, Scene};
use crate::shared::layout::{
    BvhNode, INSTANCE_IDENTITY, Instance, NO_MATERIAL, Sphere, TRIANGLE_BIT, Triangle,
};

/// What the two-level build gives: every node (top level first), the bottom trees'
/// primitive ids, and the instances (the kernel's `instance_at` records).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TwoLevel {
    /// The top-level tree from node 0, then the bottom-level trees.
    pub nodes: Vec<BvhNode>,
    /// The bottom-level trees' primitive ids.
    pub prim_ids: Vec<u32>,
    /// The instances, indexed by the top-level leaves' `first`.
    pub instances: Vec<Instance>,
}

/// A box's lower and upper corners.
type Box3 = ([f32; 3], [f32; 3]);

/// Relative widening of an instance's world box: the map's rounding (a few ULP of the
/// coordinates), many times over.
const PAD: f64 = 1.0 / 262_144.0;

/// Builds the two levels of `scene` over its flat `spheres` and `triangles` (in scene
/// order); `bvh` builds (or reads from the cache) one bottom-level tree.
pub fn build(
    scene: &Scene,
    spheres: &[Sphere],
    triangles: &[Triangle],
    bvh: &dyn Fn(&[Sphere], &[Triangle]) -> Bvh,
) -> TwoLevel {
    let placed: Vec<bool> = (0..scene.named.len())
        .map(|k| scene.instances.iter().any(|x| x.mesh == k))
        .collect();
    // The scene's own triangles: those of no placed mesh (a hidden mesh is always placed).
    let mut own_ids = Vec::new();
    let mut next = 0usize;
    let mut ranges: Vec<_> = (0..scene.named.len())
        .filter(|&k| placed[k])
        .map(|k| scene.named[k].triangles.clone())
        .collect();
    ranges.sort_by_key(|r| r.start);
    for r in &ranges {
        own_ids.extend(next as u32..r.start as u32);
        next = next.max(r.end);
    }
    own_ids.extend(next as u32..triangles.len() as u32);

    let mut out = TwoLevel::default();
    let mut bottoms: Vec<(Bvh, u32)> = Vec::new(); // (tree, id offset; u32::MAX: own ids)
    let own: Vec<Triangle> = own_ids.iter().map(|&k| triangles[k as usize]).collect();
    let own_tree = bottoms.len();
    bottoms.push((bvh(spheres, &own), u32::MAX));
    drop(own);
    let mut mesh_tree = vec![usize::MAX; scene.named.len()];
    for (k, m) in scene.named.iter().enumerate() {
        if placed[k] {
            mesh_tree[k] = bottoms.len();
            let tree = bvh(&[], &triangles[m.triangles.clone()]);
            bottoms.push((tree, m.triangles.start as u32));
        }
    }
    // A bottom tree's root box; none for an empty tree.
    let root = |t: usize| -> Option<Box3> { bottoms[t].0.nodes.first().map(|n| (n.lo, n.hi)) };
    // Lay the bottom trees out after the top level's nodes (2n - 1 for n instances).
    let mut placements: Vec<(usize, Affine, Affine, u32)> =
        vec![(own_tree, IDENTITY, IDENTITY, NO_MATERIAL)];
    for (k, m) in scene.named.iter().enumerate() {
        if placed[k] && !m.hidden {
            placements.push((mesh_tree[k], IDENTITY, IDENTITY, NO_MATERIAL));
        }
    }
    for x in &scene.instances {
        placements.push((
            mesh_tree[x.mesh],
            x.to_world,
            x.to_object,
            x.material.unwrap_or(NO_MATERIAL),
        ));
    }
    placements.retain(|p| root(p.0).is_some());
    let n_top = (2 * placements.len()).saturating_sub(1);
    let mut base = vec![0u32; bottoms.len()];
    let mut at = n_top as u32;
    for (b, (tree, _)) in base.iter_mut().zip(&bottoms) {
        *b = at;
        at += tree.nodes.len() as u32;
    }
    let mut boxes = Vec::with_capacity(placements.len());
    for &(tree, to_world, to_object, material) in &placements {
        let (lo, hi) = root(tree).expect("retained");
        let identity = to_world == IDENTITY && to_object == IDENTITY;
        boxes.push(if identity {
            (lo, hi)
        } else {
            world_box(&to_world, lo, hi)
        });
        out.instances.push(Instance {
            to_object,
            to_world,
            root: base[tree] | if identity { INSTANCE_IDENTITY } else { 0 },
            material,
            ..Instance::default()
        });
    }
    out.nodes = build_top(&boxes);
    debug_assert_eq!(out.nodes.len(), n_top);
    for (k, (tree, offset)) in bottoms.into_iter().enumerate() {
        let prim_base = out.prim_ids.len() as u32;
        out.nodes.extend(tree.nodes.iter().map(|n| {
            let mut n = *n;
            n.first += if n.count_axis >> 2 == 0 {
                base[k]
            } else {
                prim_base
            };
            n
        }));
        out.prim_ids.extend(tree.prim_ids.iter().map(|&id| {
            if id & TRIANGLE_BIT == 0 {
                id
            } else if offset == u32::MAX {
                own_ids[(id & !TRIANGLE_BIT) as usize] | TRIANGLE_BIT
            } else {
                ((id & !TRIANGLE_BIT) + offset) | TRIANGLE_BIT
            }
        }));
    }
    out
}

/// The world box of the object box (lo, hi) under `to_world`: its eight corners mapped in
/// f64, then widened by [`PAD`] of its size and position and rounded outwards to f32.
fn world_box(to_world: &Affine, lo: [f32; 3], hi: [f32; 3]) -> Box3 {
    let mut wlo = [f64::INFINITY; 3];
    let mut whi = [f64::NEG_INFINITY; 3];
    for corner in 0..8 {
        let p = [0, 1, 2].map(|a| if corner >> a & 1 == 0 { lo[a] } else { hi[a] } as f64);
        for r in 0..3 {
            let m = to_world[r].map(|x| x as f64);
            let q = m[0] * p[0] + m[1] * p[1] + m[2] * p[2] + m[3];
            wlo[r] = wlo[r].min(q);
            whi[r] = whi[r].max(q);
        }
    }
    let size = (0..3).fold(0.0f64, |m, k| m.max(whi[k] - wlo[k]));
    let out = |x: f64, up: bool| -> f32 {
        let pad = (size + x.abs()) * PAD;
        let y = if up { x + pad } else { x - pad };
        let f = y as f32;
        // `as` rounds to nearest: step once more outwards where it rounded inwards.
        match (up, (f as f64) < y, (f as f64) > y) {
            (true, true, _) => f.next_up(),
            (false, _, true) => f.next_down(),
            _ => f,
        }
    };
    (
        [0, 1, 2].map(|k| out(wlo[k], false)),
        [0, 1, 2].map(|k| out(whi[k], true)),
    )
}

/// The top-level tree over `boxes` (one per instance), depth-first as [`Bvh`]'s: each
/// leaf one instance (count 1, `first` its index), each interior node split at the median
/// of the centres along their widest axis, so the depth is ⌈log₂ n⌉. Empty for none.
pub fn build_top(boxes: &[Box3]) -> Vec<BvhNode> {
    let mut ids: Vec<u32> = (0..boxes.len() as u32).collect();
    if boxes.is_empty() {
        return Vec::new();
    }
    top_tree(boxes, &mut ids)
}

/// Below this many instances a subtree of the top level is built on the current thread.
const TOP_PARALLEL_MIN: usize = 4096;

/// The subtree over `ids`, its interior `first` indices relative to its own start: the two
/// halves of a large one built on two threads, then joined.
fn top_tree(boxes: &[Box3], ids: &mut [u32]) -> Vec<BvhNode> {
    if ids.len() < TOP_PARALLEL_MIN {
        let mut nodes = Vec::with_capacity(2 * ids.len() - 1);
        top_node(boxes, ids, &mut nodes);
        return nodes;
    }
    let (root, mid) = top_split(boxes, ids);
    let (left, right) = ids.split_at_mut(mid);
    let (l, r) = rayon::join(|| top_tree(boxes, left), || top_tree(boxes, right));
    let mut nodes = Vec::with_capacity(1 + l.len() + r.len());
    nodes.push(BvhNode {
        first: 1 + l.len() as u32,
        ..root
    });
    for part in [l, r] {
        let at = nodes.len() as u32;
        nodes.extend(part.into_iter().map(|mut n| {
            if n.count_axis >> 2 == 0 {
                n.first += at;
            }
            n
        }));
    }
    nodes
}

/// The node over `ids`: a leaf where there is one (count 1, `first` its index), else an
/// interior node (its `first` unset) and where `ids` split, at the median of the centres
/// along their widest axis (`ids` reordered so; ties by index, so the tree is the same on
/// any number of threads).
fn top_split(boxes: &[Box3], ids: &mut [u32]) -> (BvhNode, usize) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    let mut clo = [f32::INFINITY; 3];
    let mut chi = [f32::NEG_INFINITY; 3];
    for &id in ids.iter() {
        let (l, h) = boxes[id as usize];
        for k in 0..3 {
            lo[k] = lo[k].min(l[k]);
            hi[k] = hi[k].max(h[k]);
            let c = l[k] * 0.5 + h[k] * 0.5;
            clo[k] = clo[k].min(c);
            chi[k] = chi[k].max(c);
        }
    }
    if let [id] = ids {
        let leaf = BvhNode {
            lo,
            first: *id,
            hi,
            count_axis: 1 << 2,
        };
        return (leaf, 0);
    }
    let axis = (0..3)
        .max_by(|&a, &b| (chi[a] - clo[a]).total_cmp(&(chi[b] - clo[b])))
        .unwrap_or(0);
    let centre = |id: &u32| {
        let (l, h) = boxes[*id as usize];
        l[axis] * 0.5 + h[axis] * 0.5
    };
    let mid = ids.len() / 2;
    ids.select_nth_unstable_by(mid, |a, b| centre(a).total_cmp(&centre(b)).then(a.cmp(b)));
    let node = BvhNode {
        lo,
        first: 0,
        hi,
        count_axis: axis as u32,
    };
    (node, mid)
}

/// The subtree over `ids` on this thread, appended depth-first to `nodes` (interior
/// `first` indices relative to the start of `nodes`).
fn top_node(boxes: &[Box3], ids: &mut [u32], nodes: &mut Vec<BvhNode>) {
    let (node, mid) = top_split(boxes, ids);
    let at = nodes.len();
    nodes.push(node);
    if mid == 0 {
        return;
    }
    let (left, right) = ids.split_at_mut(mid);
    top_node(boxes, left, nodes);
    nodes[at].first = nodes.len() as u32;
    top_node(boxes, right, nodes);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_top_level_has_one_instance_a_leaf_and_every_instance_once() {
        let boxes: Vec<_> = (0..37)
            .map(|k| {
                let x = (k * 7 % 37) as f32;
                ([x, 0.0, 0.0], [x + 0.5, 1.0, 1.0])
            })
            .collect();
        let nodes = build_top(&boxes);
        assert_eq!(nodes.len(), 2 * 37 - 1);
        let mut seen: Vec<u32> = nodes
            .iter()
            .filter(|n| n.count_axis >> 2 == 1)
            .map(|n| n.first)
            .collect();
        seen.sort();
        assert_eq!(seen, (0..37).collect::<Vec<_>>());
    }

    /// The tree built in parallel (above `TOP_PARALLEL_MIN`) is the one built on one
    /// thread, node for node.
    #[test]
    fn the_parallel_top_level_is_the_sequential_one() {
        let n = 3 * TOP_PARALLEL_MIN + 17;
        let boxes: Vec<_> = (0..n)
            .map(|k| {
                let (x, z) = ((k * 7919 % n) as f32, (k % 101) as f32);
                ([x, 0.0, z], [x + 0.5, 1.0, z + 2.0])
            })
            .collect();
        let parallel = build_top(&boxes);
        let mut ids: Vec<u32> = (0..n as u32).collect();
        let mut sequential = Vec::new();
        top_node(&boxes, &mut ids, &mut sequential);
        assert_eq!(parallel.len(), 2 * n - 1);
        assert!(parallel == sequential);
    }

    #[test]
    fn a_world_box_holds_the_mapped_corners() {
        let (to_world, _) = (
            [
                [0.0, -2.0, 0.0, 1.0],
                [2.0, 0.0, 0.0, -3.0],
                [0.0, 0.0, 0.5, 0.25],
            ],
            (),
        );
        let (lo, hi) = world_box(&to_world, [-1.0, -1.0, -1.0], [1.0, 2.0, 3.0]);
        assert!(lo[0] <= -3.0 && hi[0] >= 3.0, "{lo:?} {hi:?}");
        assert!(lo[1] <= -5.0 && hi[1] >= -1.0, "{lo:?} {hi:?}");
        assert!(lo[2] <= -0.25 && hi[2] >= 1.75, "{lo:?} {hi:?}");
        assert!(hi[0] < 3.001 && lo[1] > -5.001);
    }
}
