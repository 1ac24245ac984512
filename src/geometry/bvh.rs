//! A bounding-volume hierarchy over triangles (median split on the longest
//! axis of the centroids, up to 4 triangles per leaf), used for the
//! self-intersection test and for closest-point queries.

use super::vec3::*;
use super::TriMesh;

/// Axis-aligned box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    pub min: [f64; 3],
    pub max: [f64; 3],
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb { min: [f64::INFINITY; 3], max: [f64::NEG_INFINITY; 3] };

    pub fn of_points(points: &[[f64; 3]]) -> Aabb {
        points.iter().fold(Aabb::EMPTY, |b, p| b.grow(*p))
    }

    #[allow(clippy::needless_range_loop)]
    pub fn grow(mut self, p: [f64; 3]) -> Aabb {
        for k in 0..3 {
            self.min[k] = self.min[k].min(p[k]);
            self.max[k] = self.max[k].max(p[k]);
        }
        self
    }

    pub fn union(self, o: Aabb) -> Aabb {
        self.grow(o.min).grow(o.max)
    }

    pub fn overlaps(&self, o: &Aabb) -> bool {
        (0..3).all(|k| self.min[k] <= o.max[k] && o.min[k] <= self.max[k])
    }

    /// Squared distance from p to the box (0 inside).
    pub fn dist2(&self, p: [f64; 3]) -> f64 {
        (0..3)
            .map(|k| {
                let d = (self.min[k] - p[k]).max(0.0).max(p[k] - self.max[k]);
                d * d
            })
            .sum()
    }

    pub fn centre(&self) -> [f64; 3] {
        scale(add(self.min, self.max), 0.5)
    }

    pub fn size(&self) -> [f64; 3] {
        sub(self.max, self.min)
    }

    pub fn diagonal(&self) -> f64 {
        norm(self.size())
    }
}

#[derive(Debug, Clone)]
struct Node {
    bb: Aabb,
    /// Leaf: first index into `order`; interior: index of the left child (right = left + 1 is NOT assumed).
    first: u32,
    /// Leaf: number of triangles (> 0); interior: 0.
    count: u32,
    /// Interior: index of the right child.
    right: u32,
}

/// A BVH over the triangles of a mesh (indices only; the caller keeps the mesh).
#[derive(Debug, Clone)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
}

const LEAF: usize = 4;

impl Bvh {
    /// Build over triangles whose indices are in range (others are left out).
    pub fn new(mesh: &TriMesh) -> Bvh {
        let nv = mesh.vertices.len();
        let boxes: Vec<Aabb> = mesh
            .triangles
            .iter()
            .map(|t| {
                if t.iter().all(|&v| (v as usize) < nv) {
                    Aabb::of_points(&t.map(|v| mesh.vertices[v as usize]))
                } else {
                    Aabb::EMPTY
                }
            })
            .collect();
        Self::from_boxes(&boxes)
    }

    /// Build over arbitrary boxes (empty boxes are left out).
    pub fn from_boxes(boxes: &[Aabb]) -> Bvh {
        let mut order: Vec<u32> = (0..boxes.len() as u32).filter(|&i| boxes[i as usize].min[0] <= boxes[i as usize].max[0]).collect();
        let centres: Vec<[f64; 3]> = boxes.iter().map(|b| b.centre()).collect();
        let mut nodes = Vec::with_capacity(2 * order.len() / LEAF + 1);
        if !order.is_empty() {
            let n = order.len();
            build(&mut nodes, &mut order, 0, n, boxes, &centres);
        }
        Bvh { nodes, order }
    }

    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Call `f` with every item whose box overlaps `bb`.
    pub fn for_each_overlap(&self, bb: &Aabb, mut f: impl FnMut(u32)) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = vec![0u32];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n as usize];
            if !node.bb.overlaps(bb) {
                continue;
            }
            if node.count > 0 {
                for &i in &self.order[node.first as usize..(node.first + node.count) as usize] {
                    f(i);
                }
            } else {
                stack.push(node.first);
                stack.push(node.right);
            }
        }
    }

    /// The item minimising `d2(item)` (a squared distance from p that is never
    /// below the squared distance from p to the item's box). None when empty.
    pub fn nearest(&self, p: [f64; 3], mut d2: impl FnMut(u32) -> f64) -> Option<(u32, f64)> {
        if self.nodes.is_empty() {
            return None;
        }
        let mut best = (u32::MAX, f64::INFINITY);
        let mut stack = vec![(0u32, self.nodes[0].bb.dist2(p))];
        while let Some((n, bd)) = stack.pop() {
            if bd >= best.1 {
                continue;
            }
            let node = &self.nodes[n as usize];
            if node.count > 0 {
                for &i in &self.order[node.first as usize..(node.first + node.count) as usize] {
                    let d = d2(i);
                    if d < best.1 || (d == best.1 && i < best.0) {
                        best = (i, d);
                    }
                }
            } else {
                let (l, r) = (node.first, node.right);
                let (dl, dr) = (self.nodes[l as usize].bb.dist2(p), self.nodes[r as usize].bb.dist2(p));
                // visit the nearer child first (pushed last)
                if dl <= dr {
                    stack.push((r, dr));
                    stack.push((l, dl));
                } else {
                    stack.push((l, dl));
                    stack.push((r, dr));
                }
            }
        }
        (best.0 != u32::MAX).then_some(best)
    }
}

fn build(nodes: &mut Vec<Node>, order: &mut [u32], lo: usize, hi: usize, boxes: &[Aabb], centres: &[[f64; 3]]) -> u32 {
    let me = nodes.len() as u32;
    let bb = order[lo..hi].iter().fold(Aabb::EMPTY, |b, &i| b.union(boxes[i as usize]));
    nodes.push(Node { bb, first: lo as u32, count: (hi - lo) as u32, right: 0 });
    if hi - lo <= LEAF {
        return me;
    }
    let cb = order[lo..hi].iter().fold(Aabb::EMPTY, |b, &i| b.grow(centres[i as usize]));
    let s = cb.size();
    let axis = if s[0] >= s[1] && s[0] >= s[2] { 0 } else if s[1] >= s[2] { 1 } else { 2 };
    let mid = (lo + hi) / 2;
    order[lo..hi].select_nth_unstable_by(mid - lo, |&a, &b| {
        centres[a as usize][axis].total_cmp(&centres[b as usize][axis]).then(a.cmp(&b))
    });
    let left = build(nodes, order, lo, mid, boxes, centres);
    let right = build(nodes, order, mid, hi, boxes, centres);
    let node = &mut nodes[me as usize];
    node.first = left;
    node.count = 0;
    node.right = right;
    me
}

/// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection 5.1.5),
/// with its barycentric coordinates.
pub fn closest_point_on_triangle(p: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(p, a);
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, [1.0, 0.0, 0.0]);
    }
    let bp = sub(p, b);
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (add(a, scale(ab, v)), [1.0 - v, v, 0.0]);
    }
    let cp = sub(p, c);
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (add(a, scale(ac, w)), [1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (add(b, scale(sub(c, b), w)), [0.0, 1.0 - w, w]);
    }
    let denom = va + vb + vc;
    if denom == 0.0 || denom.is_nan() {
        // degenerate triangle: fall back to its corners
        let best = [(a, [1.0, 0.0, 0.0]), (b, [0.0, 1.0, 0.0]), (c, [0.0, 0.0, 1.0])]
            .into_iter()
            .min_by(|x, y| dist2(p, x.0).total_cmp(&dist2(p, y.0)))
            .unwrap();
        return best;
    }
    let v = vb / denom;
    let w = vc / denom;
    (add(a, add(scale(ab, v), scale(ac, w))), [1.0 - v - w, v, w])
}

/// Closest-point queries on a triangle surface (for distances and Hausdorff measures).
#[derive(Debug, Clone)]
pub struct SurfaceLocator {
    vertices: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    bvh: Bvh,
}

/// Result of [`SurfaceLocator::closest_detailed`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosestPoint {
    pub point: [f64; 3],
    pub triangle: u32,
    pub bary: [f64; 3],
    pub distance: f64,
}

impl SurfaceLocator {
    /// Keeps a copy of the mesh. Triangles with out-of-range indices are ignored.
    pub fn new(mesh: &TriMesh) -> SurfaceLocator {
        SurfaceLocator { vertices: mesh.vertices.clone(), triangles: mesh.triangles.clone(), bvh: Bvh::new(mesh) }
    }

    /// The closest surface point to p, its triangle and the distance.
    /// Ties go to the lowest triangle id. Panics never; on a mesh without
    /// triangles it returns (p, u32::MAX, inf).
    pub fn closest(&self, p: [f64; 3]) -> ([f64; 3], u32, f64) {
        match self.closest_detailed(p) {
            Some(c) => (c.point, c.triangle, c.distance),
            None => (p, u32::MAX, f64::INFINITY),
        }
    }

    /// Like [`SurfaceLocator::closest`] with barycentric coordinates; None without triangles.
    pub fn closest_detailed(&self, p: [f64; 3]) -> Option<ClosestPoint> {
        let tri = |t: u32| self.triangles[t as usize].map(|v| self.vertices[v as usize]);
        let (t, d2) = self.bvh.nearest(p, |t| {
            let [a, b, c] = tri(t);
            dist2(p, closest_point_on_triangle(p, a, b, c).0)
        })?;
        let [a, b, c] = tri(t);
        let (point, bary) = closest_point_on_triangle(p, a, b, c);
        Some(ClosestPoint { point, triangle: t, bary, distance: d2.sqrt() })
    }

    /// One-sided Hausdorff distance from `points` to the surface: the largest closest-point distance.
    pub fn max_distance(&self, points: &[[f64; 3]]) -> f64 {
        use rayon::prelude::*;
        points.par_iter().map(|&p| self.closest(p).2).reduce(|| 0.0, f64::max)
    }
}
