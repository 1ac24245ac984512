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

pub(crate) fn check(mesh: &TriMesh) -> MeshReport {
    let nv = mesh.vertices.len();
    let nt = mesh.triangles.len();
    let mut issues = Vec::new();
    let pos = |v: u32| mesh.vertices.get(v as usize).copied().unwrap_or([f64::NAN; 3]);

    if nt == 0 {
        issues.push(Issue {
            kind: IssueKind::Empty,
            severity: Severity::Error,
            count: 0,
            message: format!("empty mesh: no triangles ({nv} vertices)"),
            vertices: vec![],
            triangles: vec![],
        });
    }

    // --- non-finite coordinates
    let non_finite: Vec<u32> = (0..nv as u32).filter(|&v| !pos(v).iter().all(|c| c.is_finite())).collect();
    if let Some(&v) = non_finite.first() {
        issues.push(Issue {
            kind: IssueKind::NonFinite,
            severity: Severity::Error,
            count: non_finite.len(),
            message: format!("non-finite coordinates: {} vertices; first vertex {v} = {}", non_finite.len(), fmt_p(pos(v))),
            vertices: vec![v],
            triangles: vec![],
        });
    }

    // --- index range and collapsed triangles
    let out_of_range: Vec<usize> = (0..nt).filter(|&t| mesh.triangles[t].iter().any(|&v| v as usize >= nv)).collect();
    if let Some(&t) = out_of_range.first() {
        issues.push(Issue {
            kind: IssueKind::IndexOutOfRange,
            severity: Severity::Error,
            count: out_of_range.len(),
            message: format!(
                "vertex index out of range: {} triangles; first triangle {t} = {:?} with {nv} vertices",
                out_of_range.len(),
                mesh.triangles[t]
            ),
            vertices: vec![],
            triangles: vec![t as u32],
        });
    }
    let valid_tri = |t: usize| mesh.triangles[t].iter().all(|&v| (v as usize) < nv);
    let collapsed: Vec<usize> = (0..nt)
        .filter(|&t| {
            let [a, b, c] = mesh.triangles[t];
            valid_tri(t) && (a == b || b == c || a == c)
        })
        .collect();
    if let Some(&t) = collapsed.first() {
        let tri = mesh.triangles[t];
        issues.push(Issue {
            kind: IssueKind::CollapsedTriangles,
            severity: Severity::Error,
            count: collapsed.len(),
            message: format!(
                "collapsed triangles: {} triangles repeat a vertex (welding merges vertices closer than the weld tolerance times the bounding-box diagonal: if the part is thinner than that, lower the weld tolerance, --weld-tolerance / LoadOptions::weld_tolerance); first triangle {t} = ({}, {}, {}) at {}",
                collapsed.len(),
                tri[0],
                tri[1],
                tri[2],
                fmt_p(pos(tri[0]))
            ),
            vertices: tri.to_vec(),
            triangles: vec![t as u32],
        });
    }

    // --- referenced vertices
    let mut referenced = vec![false; nv];
    for t in 0..nt {
        if valid_tri(t) {
            for &v in &mesh.triangles[t] {
                referenced[v as usize] = true;
            }
        }
    }
    let n_ref = referenced.iter().filter(|r| **r).count();
    let unreferenced = nv - n_ref;
    if unreferenced > 0 {
        let first = referenced.iter().position(|r| !r).unwrap() as u32;
        issues.push(Issue {
            kind: IssueKind::UnreferencedVertices,
            severity: Severity::Warning,
            count: unreferenced,
            message: format!(
                "{unreferenced} vertices are used by no triangle (ignored); first vertex {first} at {}",
                fmt_p(pos(first))
            ),
            vertices: vec![first],
            triangles: vec![],
        });
    }

    // --- edges: boundary, non-manifold, orientation
    let et = EdgeTable::new(mesh);
    let mut boundary = Vec::new();
    let mut non_manifold = Vec::new();
    let mut inconsistent = Vec::new();
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
    let edge_at = |ei: usize| {
        let [a, b] = et.edges[ei].0;
        format!("({a}, {b}) from {} to {}", fmt_p(pos(a)), fmt_p(pos(b)))
    };
    let edge_tris = |ei: usize| et.incidences(&et.edges[ei]).iter().map(|x| x.0).collect::<Vec<_>>();

    // boundary loops: components of the boundary-edge graph
    let mut uf_b = UnionFind::new(nv);
    for &ei in &boundary {
        let [a, b] = et.edges[ei].0;
        uf_b.union(a, b);
    }
    let mut loop_roots: Vec<u32> = boundary.iter().map(|&ei| uf_b.find(et.edges[ei].0[0])).collect();
    loop_roots.sort_unstable();
    loop_roots.dedup();
    let boundary_loops = loop_roots.len();
    if let Some(&ei) = boundary.first() {
        issues.push(Issue {
            kind: IssueKind::BoundaryEdges,
            severity: Severity::Error,
            count: boundary.len(),
            message: format!(
                "open surface: {} boundary edges in {} loops; first boundary edge {}",
                boundary.len(),
                boundary_loops,
                edge_at(ei)
            ),
            vertices: et.edges[ei].0.to_vec(),
            triangles: edge_tris(ei),
        });
    }
    if let Some(&ei) = non_manifold.first() {
        issues.push(Issue {
            kind: IssueKind::NonManifoldEdges,
            severity: Severity::Error,
            count: non_manifold.len(),
            message: format!(
                "non-manifold edges: {} edges shared by more than two triangles; first edge {} shared by {} triangles",
                non_manifold.len(),
                edge_at(ei),
                edge_tris(ei).len()
            ),
            vertices: et.edges[ei].0.to_vec(),
            triangles: edge_tris(ei),
        });
    }

    // --- vertex manifoldness: fans of triangles around each vertex, joined through shared edges
    let mut vt_start = vec![0usize; nv + 1];
    for t in 0..nt {
        if valid_tri(t) && collapsed.binary_search(&t).is_err() {
            for &v in &mesh.triangles[t] {
                vt_start[v as usize + 1] += 1;
            }
        }
    }
    for v in 0..nv {
        vt_start[v + 1] += vt_start[v];
    }
    let mut vt = vec![0u32; vt_start[nv]];
    let mut fill = vt_start.clone();
    for t in 0..nt {
        if valid_tri(t) && collapsed.binary_search(&t).is_err() {
            for &v in &mesh.triangles[t] {
                vt[fill[v as usize]] = t as u32;
                fill[v as usize] += 1;
            }
        }
    }
    let mut non_manifold_vertices = Vec::new();
    let mut local: Vec<u32> = Vec::new();
    let mut nbr: Vec<(u32, u32)> = Vec::new();
    for v in 0..nv {
        let tris = &vt[vt_start[v]..vt_start[v + 1]];
        if tris.len() < 2 {
            continue;
        }
        // local union-find over the fan: triangles sharing an edge (v, w) are joined
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
                let (a, b) = (find(&mut local, pair[0].1), find(&mut local, pair[1].1));
                if a != b {
                    local[a.max(b) as usize] = a.min(b);
                }
            }
        }
        let fans = (0..tris.len() as u32).filter(|&k| find(&mut local, k) == k).count();
        if fans > 1 {
            non_manifold_vertices.push((v as u32, fans));
        }
    }
    if let Some(&(v, fans)) = non_manifold_vertices.first() {
        issues.push(Issue {
            kind: IssueKind::NonManifoldVertices,
            severity: Severity::Error,
            count: non_manifold_vertices.len(),
            message: format!(
                "non-manifold vertices: {} vertices where separate fans of triangles meet (pinched); first vertex {v} at {} joins {fans} fans",
                non_manifold_vertices.len(),
                fmt_p(pos(v))
            ),
            vertices: vec![v],
            triangles: vt[vt_start[v as usize]..vt_start[v as usize + 1]].to_vec(),
        });
    }

    // --- connected components (through shared vertices)
    let mut uf = UnionFind::new(nv);
    for t in 0..nt {
        if valid_tri(t) {
            let [a, b, c] = mesh.triangles[t];
            uf.union(a, b);
            uf.union(a, c);
        }
    }
    let mut comp_tris: std::collections::BTreeMap<u32, usize> = Default::default();
    for t in 0..nt {
        if valid_tri(t) {
            *comp_tris.entry(uf.find(mesh.triangles[t][0])).or_default() += 1;
        }
    }
    let components = comp_tris.len();
    if components > 1 {
        let mut sizes: Vec<(usize, u32)> = comp_tris.iter().map(|(&r, &n)| (n, r)).collect();
        sizes.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
        let shown: Vec<String> = sizes.iter().take(8).map(|s| s.0.to_string()).collect();
        let more = if sizes.len() > 8 { ", ..." } else { "" };
        let second = sizes[1].1;
        issues.push(Issue {
            kind: IssueKind::MultipleComponents,
            severity: Severity::Error,
            count: components,
            message: format!(
                "{components} connected components (one solid is needed); triangles per component: {}{more}; the second largest contains vertex {second} at {}",
                shown.join(", "),
                fmt_p(pos(second))
            ),
            vertices: vec![second],
            triangles: vec![],
        });
    }

    // --- measures (relative to the bounding-box centre for accuracy)
    let (bmin, bmax) = if n_ref > 0 {
        let bb = (0..nv).filter(|&v| referenced[v]).fold(Aabb::EMPTY, |b, v| b.grow(mesh.vertices[v]));
        (bb.min, bb.max)
    } else {
        ([f64::NAN; 3], [f64::NAN; 3])
    };
    let centre = [0.5 * (bmin[0] + bmax[0]), 0.5 * (bmin[1] + bmax[1]), 0.5 * (bmin[2] + bmax[2])];
    let diag = norm(sub(bmax, bmin));
    let mut volume = 0.0;
    let mut area = 0.0;
    let mut degenerate = Vec::new();
    for t in 0..nt {
        if !valid_tri(t) {
            continue;
        }
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
        issues.push(Issue {
            kind: IssueKind::DegenerateTriangles,
            severity: Severity::Warning,
            count: degenerate.len(),
            message: format!(
                "{} triangles of (nearly) zero area; first triangle {t} = ({}, {}, {}) at {}",
                degenerate.len(),
                tri[0],
                tri[1],
                tri[2],
                fmt_p(pos(tri[0]))
            ),
            vertices: tri.to_vec(),
            triangles: vec![t as u32],
        });
    }

    let closed = boundary.is_empty() && nt > 0;
    let manifold = non_manifold.is_empty() && non_manifold_vertices.is_empty();
    let orientation_consistent = inconsistent.is_empty() && non_manifold.is_empty();
    if let Some(&ei) = inconsistent.first() {
        issues.push(Issue {
            kind: IssueKind::InconsistentOrientation,
            severity: Severity::Error,
            count: inconsistent.len(),
            message: format!(
                "inconsistent orientation: {} edges are traversed in the same direction by both of their triangles; first edge {} (triangles {:?}); the explicit repair option repair_orientation re-orients a closed manifold",
                inconsistent.len(),
                edge_at(ei),
                edge_tris(ei)
            ),
            vertices: et.edges[ei].0.to_vec(),
            triangles: edge_tris(ei),
        });
    }
    let oriented_outward = orientation_consistent && closed && volume > 0.0;
    if orientation_consistent && closed && manifold && (volume <= 0.0 || volume.is_nan()) && nt > 0 && non_finite.is_empty() {
        issues.push(Issue {
            kind: IssueKind::InwardOrientation,
            severity: Severity::Error,
            count: nt,
            message: format!(
                "inward orientation: signed volume {volume} is not positive (triangles must be counter-clockwise seen from outside); the explicit repair option repair_orientation flips it"
            ),
            vertices: vec![],
            triangles: vec![],
        });
    }

    // --- Euler characteristic and genus
    let euler = n_ref as i64 - et.edges.len() as i64 + (nt - collapsed.len() - out_of_range.len()) as i64;
    let genus = if closed && manifold && collapsed.is_empty() && out_of_range.is_empty() && (2 * components as i64 - euler) % 2 == 0 {
        Some((2 * components as i64 - euler) / 2)
    } else {
        None
    };

    // --- self-intersections (only meaningful on finite, in-range data)
    let self_intersecting_pairs = if non_finite.is_empty() && out_of_range.is_empty() && nt > 0 {
        let pairs = super::intersect::self_intersections(mesh, usize::MAX);
        if let Some(&(s, t)) = pairs.first() {
            let ts = mesh.triangles[s as usize];
            issues.push(Issue {
                kind: IssueKind::SelfIntersections,
                severity: Severity::Warning,
                count: pairs.len(),
                message: format!(
                    "self-intersection: {} pairs of triangles cross each other; first pair {s} and {t} near {}",
                    pairs.len(),
                    fmt_p(pos(ts[0]))
                ),
                vertices: ts.to_vec(),
                triangles: vec![s, t],
            });
        }
        pairs.len()
    } else {
        0
    };

    let can_proceed = !issues.iter().any(|i| i.severity == Severity::Error);
    MeshReport {
        vertices: nv,
        triangles: nt,
        edges: et.edges.len(),
        components,
        boundary_edges: boundary.len(),
        boundary_loops,
        non_manifold_edges: non_manifold.len(),
        non_manifold_vertices: non_manifold_vertices.len(),
        inconsistent_edges: inconsistent.len(),
        collapsed_triangles: collapsed.len(),
        degenerate_triangles: degenerate.len(),
        self_intersecting_pairs,
        unreferenced_vertices: unreferenced,
        non_finite_vertices: non_finite.len(),
        closed,
        manifold,
        orientation_consistent,
        oriented_outward,
        euler_characteristic: euler,
        genus,
        volume,
        area,
        bbox_min: bmin,
        bbox_max: bmax,
        bbox_diagonal: diag,
        can_proceed,
        issues,
    }
}
