//! The check report: topology (edges, components, manifoldness, orientation,
//! Euler characteristic, genus), geometry (volume, area, bounding box,
//! degenerate triangles, self-intersections) and the issues that stop a mesh.

use super::TriMesh;
use crate::error::Error;
use crate::geometry::vec3::{cross, dot, norm, sub};
use crate::geometry::{Aabb, UnionFind};
use serde::Serialize;

/// Triangles whose area is below this times their longest edge squared are degenerate.
pub const DEGENERATE_AREA_RATIO: f64 = 1e-12;

/// How much an issue matters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Severity {
    /// The mesh cannot go on to meshing.
    Error,
    /// Reported, but the pipeline can go on.
    Warning,
}

/// What is wrong.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum IssueKind {
    Empty,
    NonFinite,
    IndexOutOfRange,
    CollapsedTriangles,
    BoundaryEdges,
    NonManifoldEdges,
    NonManifoldVertices,
    InconsistentOrientation,
    InwardOrientation,
    MultipleComponents,
    DegenerateTriangles,
    SelfIntersections,
    UnreferencedVertices,
}

/// One problem found by the check, with where it first occurs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Issue {
    pub kind: IssueKind,
    pub severity: Severity,
    /// How many edges / vertices / triangles / pairs / components are affected.
    pub count: usize,
    /// A sentence naming what is wrong and where (first offending item with ids and coordinates).
    pub message: String,
    /// Vertex ids of the first offending item (an edge's two ends, a vertex, a triangle's corners).
    pub vertices: Vec<u32>,
    /// Triangle ids of the first offending item.
    pub triangles: Vec<u32>,
}

/// Everything the check measured. Counts refer to the mesh as loaded (after welding).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeshReport {
    pub vertices: usize,
    pub triangles: usize,
    /// Distinct undirected edges.
    pub edges: usize,
    /// Connected components (triangles sharing a vertex are connected).
    pub components: usize,
    pub boundary_edges: usize,
    /// Connected pieces of the boundary-edge graph (holes).
    pub boundary_loops: usize,
    /// Edges shared by more than two triangles.
    pub non_manifold_edges: usize,
    /// Vertices where two or more separate fans of triangles meet.
    pub non_manifold_vertices: usize,
    /// Interior edges whose two triangles traverse them in the same direction.
    pub inconsistent_edges: usize,
    /// Triangles with a repeated vertex index.
    pub collapsed_triangles: usize,
    /// Triangles with distinct corners but (nearly) zero area.
    pub degenerate_triangles: usize,
    /// Pairs of triangles that cross each other (see docs/mesh-checks.md for the test).
    pub self_intersecting_pairs: usize,
    pub unreferenced_vertices: usize,
    pub non_finite_vertices: usize,
    /// No boundary edges.
    pub closed: bool,
    /// No non-manifold edges or vertices.
    pub manifold: bool,
    /// Every interior manifold edge traversed once in each direction.
    pub orientation_consistent: bool,
    /// Consistent and the signed volume is positive (counter-clockwise seen from outside).
    pub oriented_outward: bool,
    /// V - E + F.
    pub euler_characteristic: i64,
    /// (2 C - chi) / 2, total over components; None unless closed and manifold.
    pub genus: Option<i64>,
    /// Signed volume enclosed (divergence theorem, relative to the bounding-box centre).
    pub volume: f64,
    pub area: f64,
    pub bbox_min: [f64; 3],
    pub bbox_max: [f64; 3],
    pub bbox_diagonal: f64,
    /// True when no issue has severity `Error`.
    pub can_proceed: bool,
    pub issues: Vec<Issue>,
}

impl MeshReport {
    /// `Error::InvalidMesh` listing every error-severity issue, or None when the mesh can go on.
    pub fn to_error(&self) -> Option<Error> {
        let msgs: Vec<&str> = self
            .issues
            .iter()
            .filter(|i| i.severity == Severity::Error)
            .map(|i| i.message.as_str())
            .collect();
        if msgs.is_empty() {
            None
        } else {
            Some(Error::InvalidMesh(msgs.join("; ")))
        }
    }
}

/// Undirected edges with the triangles that use them, built by sorting half-edges.
pub(crate) struct EdgeTable {
    /// (lo, hi) vertex ids with a range into `inc`.
    pub edges: Vec<([u32; 2], std::ops::Range<usize>)>,
    /// (triangle, forward) where forward means the triangle traverses lo -> hi.
    pub inc: Vec<(u32, bool)>,
}

impl EdgeTable {
    /// Skips collapsed triangles and triangles with out-of-range indices.
    pub fn new(mesh: &TriMesh) -> EdgeTable {
        let nv = mesh.vertices.len() as u32;
        let mut half: Vec<(u32, u32, u32, bool)> = Vec::with_capacity(mesh.triangles.len() * 3);
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let [a, b, c] = *tri;
            if a == b || b == c || a == c || a >= nv || b >= nv || c >= nv {
                continue;
            }
            for (u, v) in [(a, b), (b, c), (c, a)] {
                half.push((u.min(v), u.max(v), t as u32, u < v));
            }
        }
        half.sort_unstable();
        let mut edges = Vec::new();
        let mut inc = Vec::with_capacity(half.len());
        let mut i = 0;
        while i < half.len() {
            let (lo, hi) = (half[i].0, half[i].1);
            let start = inc.len();
            while i < half.len() && half[i].0 == lo && half[i].1 == hi {
                inc.push((half[i].2, half[i].3));
                i += 1;
            }
            edges.push(([lo, hi], start..inc.len()));
        }
        EdgeTable { edges, inc }
    }

    pub fn incidences(&self, e: &([u32; 2], std::ops::Range<usize>)) -> &[(u32, bool)] {
        &self.inc[e.1.clone()]
    }
}

/// Signed volume of the tetrahedron (origin, a, b, c) for triangle t, origin at 0.
pub(crate) fn signed_volume_of(mesh: &TriMesh, t: usize) -> f64 {
    let [a, b, c] = mesh.triangles[t].map(|v| mesh.vertices[v as usize]);
    dot(a, cross(b, c)) / 6.0
}

/// A coordinate as messages show it: shortest round-trip decimal, in exponent form
/// when it is tiny or huge (so 2.3e-41 is not forty zeros).
fn fmt_c(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || (1e-5..1e15).contains(&a) || !a.is_finite() {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

pub(crate) fn fmt_p(p: [f64; 3]) -> String {
    format!("({}, {}, {})", fmt_c(p[0]), fmt_c(p[1]), fmt_c(p[2]))
}

/// The issues found so far and the mesh they are about; each step of [`check`] adds
/// its issue (at most one per kind, naming the first offending item).
struct Checker<'a> {
    mesh: &'a TriMesh,
    issues: Vec<Issue>,
}

/// The edge classes of the edge table.
struct EdgeClasses {
    boundary: Vec<usize>,
    non_manifold: Vec<usize>,
    inconsistent: Vec<usize>,
    boundary_loops: usize,
}

/// Volume, area, bounding box and degenerate triangles.
struct Measures {
    bmin: [f64; 3],
    bmax: [f64; 3],
    diag: f64,
    volume: f64,
    area: f64,
    degenerate: Vec<usize>,
}

impl<'a> Checker<'a> {
    fn nv(&self) -> usize {
        self.mesh.vertices.len()
    }

    fn nt(&self) -> usize {
        self.mesh.triangles.len()
    }

    fn pos(&self, v: u32) -> [f64; 3] {
        self.mesh.vertices.get(v as usize).copied().unwrap_or([f64::NAN; 3])
    }

    fn valid_tri(&self, t: usize) -> bool {
        self.mesh.triangles[t].iter().all(|&v| (v as usize) < self.nv())
    }

    fn push(&mut self, kind: IssueKind, severity: Severity, count: usize, message: String, vertices: Vec<u32>, triangles: Vec<u32>) {
        self.issues.push(Issue { kind, severity, count, message, vertices, triangles });
    }

    fn empty(&mut self) {
        if self.nt() == 0 {
            let m = format!("empty mesh: no triangles ({} vertices)", self.nv());
            self.push(IssueKind::Empty, Severity::Error, 0, m, vec![], vec![]);
        }
    }

    fn non_finite(&mut self) -> Vec<u32> {
        let non_finite: Vec<u32> = (0..self.nv() as u32).filter(|&v| !self.pos(v).iter().all(|c| c.is_finite())).collect();
        if let Some(&v) = non_finite.first() {
            let m = format!("non-finite coordinates: {} vertices; first vertex {v} = {}", non_finite.len(), fmt_p(self.pos(v)));
            self.push(IssueKind::NonFinite, Severity::Error, non_finite.len(), m, vec![v], vec![]);
        }
        non_finite
    }

    fn out_of_range(&mut self) -> Vec<usize> {
        let out_of_range: Vec<usize> = (0..self.nt()).filter(|&t| !self.valid_tri(t)).collect();
        if let Some(&t) = out_of_range.first() {
            let m = format!(
                "vertex index out of range: {} triangles; first triangle {t} = {:?} with {} vertices",
                out_of_range.len(),
                self.mesh.triangles[t],
                self.nv()
            );
            self.push(IssueKind::IndexOutOfRange, Severity::Error, out_of_range.len(), m, vec![], vec![t as u32]);
        }
        out_of_range
    }

    fn collapsed(&mut self) -> Vec<usize> {
        let collapsed: Vec<usize> = (0..self.nt())
            .filter(|&t| {
                let [a, b, c] = self.mesh.triangles[t];
                self.valid_tri(t) && (a == b || b == c || a == c)
            })
            .collect();
        if let Some(&t) = collapsed.first() {
            let tri = self.mesh.triangles[t];
            let m = format!(
                "collapsed triangles: {} triangles repeat a vertex (welding merges vertices closer than the weld tolerance times the bounding-box diagonal: if the part is thinner than that, lower the weld tolerance, --weld-tolerance / LoadOptions::weld_tolerance); first triangle {t} = ({}, {}, {}) at {}",
                collapsed.len(),
                tri[0],
                tri[1],
                tri[2],
                fmt_p(self.pos(tri[0]))
            );
            self.push(IssueKind::CollapsedTriangles, Severity::Error, collapsed.len(), m, tri.to_vec(), vec![t as u32]);
        }
        collapsed
    }

    /// Which vertices a valid triangle uses, and how many.
    fn referenced(&mut self) -> (Vec<bool>, usize) {
        let mut referenced = vec![false; self.nv()];
        for t in 0..self.nt() {
            if self.valid_tri(t) {
                for &v in &self.mesh.triangles[t] {
                    referenced[v as usize] = true;
                }
            }
        }
        let n_ref = referenced.iter().filter(|r| **r).count();
        let unreferenced = self.nv() - n_ref;
        if unreferenced > 0 {
            let first = referenced.iter().position(|r| !r).unwrap() as u32;
            let m = format!("{unreferenced} vertices are used by no triangle (ignored); first vertex {first} at {}", fmt_p(self.pos(first)));
            self.push(IssueKind::UnreferencedVertices, Severity::Warning, unreferenced, m, vec![first], vec![]);
        }
        (referenced, n_ref)
    }

    fn edge_at(&self, et: &EdgeTable, ei: usize) -> String {
        let [a, b] = et.edges[ei].0;
        format!("({a}, {b}) from {} to {}", fmt_p(self.pos(a)), fmt_p(self.pos(b)))
    }

    /// Boundary, non-manifold and inconsistently oriented edges; the issues of the
    /// first two (the orientation issue comes later, after the measures).
    fn edges(&mut self, et: &EdgeTable) -> EdgeClasses {
        let (mut boundary, mut non_manifold, mut inconsistent) = (Vec::new(), Vec::new(), Vec::new());
        for (ei, e) in et.edges.iter().enumerate() {
            let inc = et.incidences(e);
            match inc.len() {
                1 => boundary.push(ei),
                2 => {
                    if inc[0].1 == inc[1].1 {
                        inconsistent.push(ei)
                    }
                }
                _ => non_manifold.push(ei),
            }
        }
        // boundary loops: components of the boundary-edge graph
        let mut uf_b = UnionFind::new(self.nv());
        for &ei in &boundary {
            let [a, b] = et.edges[ei].0;
            uf_b.union(a, b);
        }
        let mut loop_roots: Vec<u32> = boundary.iter().map(|&ei| uf_b.find(et.edges[ei].0[0])).collect();
        loop_roots.sort_unstable();
        loop_roots.dedup();
        let boundary_loops = loop_roots.len();
        if let Some(&ei) = boundary.first() {
            let m = format!("open surface: {} boundary edges in {} loops; first boundary edge {}", boundary.len(), boundary_loops, self.edge_at(et, ei));
            self.push(IssueKind::BoundaryEdges, Severity::Error, boundary.len(), m, et.edges[ei].0.to_vec(), edge_tris(et, ei));
        }
        if let Some(&ei) = non_manifold.first() {
            let m = format!(
                "non-manifold edges: {} edges shared by more than two triangles; first edge {} shared by {} triangles",
                non_manifold.len(),
                self.edge_at(et, ei),
                edge_tris(et, ei).len()
            );
            self.push(IssueKind::NonManifoldEdges, Severity::Error, non_manifold.len(), m, et.edges[ei].0.to_vec(), edge_tris(et, ei));
        }
        EdgeClasses { boundary, non_manifold, inconsistent, boundary_loops }
    }

    /// Vertices where two or more fans of triangles (joined through shared edges) meet.
    fn non_manifold_vertices(&mut self, collapsed: &[usize]) -> Vec<(u32, usize)> {
        let (nv, nt, mesh) = (self.nv(), self.nt(), self.mesh);
        let used = |t: usize| self.valid_tri(t) && collapsed.binary_search(&t).is_err();
        let mut vt_start = vec![0usize; nv + 1];
        for t in (0..nt).filter(|&t| used(t)) {
            for &v in &mesh.triangles[t] {
                vt_start[v as usize + 1] += 1;
            }
        }
        for v in 0..nv {
            vt_start[v + 1] += vt_start[v];
        }
        let mut vt = vec![0u32; vt_start[nv]];
        let mut fill = vt_start.clone();
        for t in (0..nt).filter(|&t| used(t)) {
            for &v in &mesh.triangles[t] {
                vt[fill[v as usize]] = t as u32;
                fill[v as usize] += 1;
            }
        }
        let mut found = Vec::new();
        let mut local: Vec<u32> = Vec::new();
        let mut nbr: Vec<(u32, u32)> = Vec::new();
        for v in 0..nv {
            let tris = &vt[vt_start[v]..vt_start[v + 1]];
            if tris.len() < 2 {
                continue;
            }
            let fans = fan_count(mesh, v, tris, &mut local, &mut nbr);
            if fans > 1 {
                found.push((v as u32, fans));
            }
        }
        if let Some(&(v, fans)) = found.first() {
            let m = format!(
                "non-manifold vertices: {} vertices where separate fans of triangles meet (pinched); first vertex {v} at {} joins {fans} fans",
                found.len(),
                fmt_p(self.pos(v))
            );
            let tris = vt[vt_start[v as usize]..vt_start[v as usize + 1]].to_vec();
            self.push(IssueKind::NonManifoldVertices, Severity::Error, found.len(), m, vec![v], tris);
        }
        found
    }

    /// Connected components through shared vertices.
    fn components(&mut self) -> usize {
        let mut uf = UnionFind::new(self.nv());
        let valid: Vec<usize> = (0..self.nt()).filter(|&t| self.valid_tri(t)).collect();
        for &t in &valid {
            let [a, b, c] = self.mesh.triangles[t];
            uf.union(a, b);
            uf.union(a, c);
        }
        let mut comp_tris: std::collections::BTreeMap<u32, usize> = Default::default();
        for &t in &valid {
            *comp_tris.entry(uf.find(self.mesh.triangles[t][0])).or_default() += 1;
        }
        let components = comp_tris.len();
        if components > 1 {
            let mut sizes: Vec<(usize, u32)> = comp_tris.iter().map(|(&r, &n)| (n, r)).collect();
            sizes.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
            let shown: Vec<String> = sizes.iter().take(8).map(|s| s.0.to_string()).collect();
            let more = if sizes.len() > 8 { ", ..." } else { "" };
            let second = sizes[1].1;
            let m = format!(
                "{components} connected components (one solid is needed); triangles per component: {}{more}; the second largest contains vertex {second} at {}",
                shown.join(", "),
                fmt_p(self.pos(second))
            );
            self.push(IssueKind::MultipleComponents, Severity::Error, components, m, vec![second], vec![]);
        }
        components
    }

    /// Volume, area and bounding box (relative to the bounding-box centre for
    /// accuracy) and the degenerate triangles.
    fn measures(&mut self, referenced: &[bool], n_ref: usize) -> Measures {
        let mesh = self.mesh;
        let (bmin, bmax) = if n_ref > 0 {
            let bb = (0..self.nv()).filter(|&v| referenced[v]).fold(Aabb::EMPTY, |b, v| b.grow(mesh.vertices[v]));
            (bb.min, bb.max)
        } else {
            ([f64::NAN; 3], [f64::NAN; 3])
        };
        let centre = [0.5 * (bmin[0] + bmax[0]), 0.5 * (bmin[1] + bmax[1]), 0.5 * (bmin[2] + bmax[2])];
        let diag = norm(sub(bmax, bmin));
        let (mut volume, mut area) = (0.0, 0.0);
        let mut degenerate = Vec::new();
        for t in (0..self.nt()).filter(|&t| self.valid_tri(t)) {
            let [a, b, c] = mesh.triangles[t].map(|v| sub(mesh.vertices[v as usize], centre));
            let n = cross(sub(b, a), sub(c, a));
            let twice = norm(n);
            area += 0.5 * twice;
            volume += dot(a, cross(b, c)) / 6.0;
            let lmax2 = dot(sub(b, a), sub(b, a)).max(dot(sub(c, b), sub(c, b))).max(dot(sub(a, c), sub(a, c)));
            let [i, j, k] = mesh.triangles[t];
            if i != j && j != k && i != k && 0.5 * twice <= DEGENERATE_AREA_RATIO * lmax2 {
                degenerate.push(t);
            }
        }
        if let Some(&t) = degenerate.first() {
            let tri = mesh.triangles[t];
            let m = format!("{} triangles of (nearly) zero area; first triangle {t} = ({}, {}, {}) at {}", degenerate.len(), tri[0], tri[1], tri[2], fmt_p(self.pos(tri[0])));
            self.push(IssueKind::DegenerateTriangles, Severity::Warning, degenerate.len(), m, tri.to_vec(), vec![t as u32]);
        }
        Measures { bmin, bmax, diag, volume, area, degenerate }
    }

    /// The orientation issues: inconsistent edges, then an inward-facing closed manifold.
    fn orientation(&mut self, et: &EdgeTable, e: &EdgeClasses, manifold: bool, volume: f64, no_non_finite: bool) {
        let closed = e.boundary.is_empty() && self.nt() > 0;
        let consistent = e.inconsistent.is_empty() && e.non_manifold.is_empty();
        if let Some(&ei) = e.inconsistent.first() {
            let m = format!(
                "inconsistent orientation: {} edges are traversed in the same direction by both of their triangles; first edge {} (triangles {:?}); the explicit repair option repair_orientation re-orients a closed manifold",
                e.inconsistent.len(),
                self.edge_at(et, ei),
                edge_tris(et, ei)
            );
            self.push(IssueKind::InconsistentOrientation, Severity::Error, e.inconsistent.len(), m, et.edges[ei].0.to_vec(), edge_tris(et, ei));
        }
        if consistent && closed && manifold && (volume <= 0.0 || volume.is_nan()) && no_non_finite {
            let m = format!(
                "inward orientation: signed volume {volume} is not positive (triangles must be counter-clockwise seen from outside); the explicit repair option repair_orientation flips it"
            );
            self.push(IssueKind::InwardOrientation, Severity::Error, self.nt(), m, vec![], vec![]);
        }
    }

    /// Pairs of crossing triangles (only meaningful on finite, in-range data).
    fn self_intersections(&mut self) -> usize {
        let pairs = super::intersect::self_intersections(self.mesh, usize::MAX);
        if let Some(&(s, t)) = pairs.first() {
            let ts = self.mesh.triangles[s as usize];
            let m = format!("self-intersection: {} pairs of triangles cross each other; first pair {s} and {t} near {}", pairs.len(), fmt_p(self.pos(ts[0])));
            self.push(IssueKind::SelfIntersections, Severity::Warning, pairs.len(), m, ts.to_vec(), vec![s, t]);
        }
        pairs.len()
    }
}

fn edge_tris(et: &EdgeTable, ei: usize) -> Vec<u32> {
    et.incidences(&et.edges[ei]).iter().map(|x| x.0).collect()
}

/// Fans of the triangles `tris` around vertex `v`: a local union-find joins the
/// triangles that share an edge (v, w). `local` and `nbr` are scratch buffers.
fn fan_count(mesh: &TriMesh, v: usize, tris: &[u32], local: &mut Vec<u32>, nbr: &mut Vec<(u32, u32)>) -> usize {
    local.clear();
    local.extend(0..tris.len() as u32);
    nbr.clear();
    for (k, &t) in tris.iter().enumerate() {
        for &w in &mesh.triangles[t as usize] {
            if w as usize != v {
                nbr.push((w, k as u32));
            }
        }
    }
    nbr.sort_unstable();
    let find = |l: &mut Vec<u32>, mut x: u32| {
        while l[x as usize] != x {
            x = l[x as usize];
        }
        x
    };
    for pair in nbr.windows(2) {
        if pair[0].0 == pair[1].0 {
            let (a, b) = (find(local, pair[0].1), find(local, pair[1].1));
            if a != b {
                local[a.max(b) as usize] = a.min(b);
            }
        }
    }
    (0..tris.len() as u32).filter(|&k| find(local, k) == k).count()
}

/// Every measure and issue of `mesh`, step by step; the issues in a fixed order
/// (emptiness, data errors, topology, measures, orientation, self-intersections).
pub(crate) fn check(mesh: &TriMesh) -> MeshReport {
    let (nv, nt) = (mesh.vertices.len(), mesh.triangles.len());
    let mut c = Checker { mesh, issues: Vec::new() };
    c.empty();
    let non_finite = c.non_finite();
    let out_of_range = c.out_of_range();
    let collapsed = c.collapsed();
    let (referenced, n_ref) = c.referenced();
    let et = EdgeTable::new(mesh);
    let e = c.edges(&et);
    let non_manifold_vertices = c.non_manifold_vertices(&collapsed);
    let components = c.components();
    let m = c.measures(&referenced, n_ref);
    let closed = e.boundary.is_empty() && nt > 0;
    let manifold = e.non_manifold.is_empty() && non_manifold_vertices.is_empty();
    let orientation_consistent = e.inconsistent.is_empty() && e.non_manifold.is_empty();
    c.orientation(&et, &e, manifold, m.volume, non_finite.is_empty());
    let oriented_outward = orientation_consistent && closed && m.volume > 0.0;
    // Euler characteristic and genus
    let euler = n_ref as i64 - et.edges.len() as i64 + (nt - collapsed.len() - out_of_range.len()) as i64;
    let genus = if closed && manifold && collapsed.is_empty() && out_of_range.is_empty() && (2 * components as i64 - euler) % 2 == 0 {
        Some((2 * components as i64 - euler) / 2)
    } else {
        None
    };
    let self_intersecting_pairs = if non_finite.is_empty() && out_of_range.is_empty() && nt > 0 { c.self_intersections() } else { 0 };
    let issues = c.issues;
    let can_proceed = !issues.iter().any(|i| i.severity == Severity::Error);
    MeshReport {
        vertices: nv,
        triangles: nt,
        edges: et.edges.len(),
        components,
        boundary_edges: e.boundary.len(),
        boundary_loops: e.boundary_loops,
        non_manifold_edges: e.non_manifold.len(),
        non_manifold_vertices: non_manifold_vertices.len(),
        inconsistent_edges: e.inconsistent.len(),
        collapsed_triangles: collapsed.len(),
        degenerate_triangles: m.degenerate.len(),
        self_intersecting_pairs,
        unreferenced_vertices: nv - n_ref,
        non_finite_vertices: non_finite.len(),
        closed,
        manifold,
        orientation_consistent,
        oriented_outward,
        euler_characteristic: euler,
        genus,
        volume: m.volume,
        area: m.area,
        bbox_min: m.bmin,
        bbox_max: m.bmax,
        bbox_diagonal: m.diag,
        can_proceed,
        issues,
    }
}
