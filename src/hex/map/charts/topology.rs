//! The chart topology the polycube demands, checked on a labelling: every face has
//! one connected chart with the face's Euler characteristic (1 for a disc, 0 for an
//! annulus), the charts meet as the faces do, and every polycube corner has one
//! input vertex where the charts of its faces meet.

use super::faces::PolycubeFaces;
use super::segment::{components, TriGraph};
use crate::mesh::TriMesh;
use crate::geometry::StableHashMap;
use std::collections::BTreeSet;
use std::fmt;

/// Measures of one chart (the triangles labelled with one face).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct ChartStats {
    pub triangles: usize,
    pub area: f64,
    /// Connected components (1 when the chart is connected).
    pub components: usize,
    /// Euler characteristic V - E + F of the chart's triangles.
    pub euler: i64,
    /// The face's Euler characteristic (2 - number of boundary loops).
    pub expected_euler: i64,
}

/// What does not match between the charts and the polycube's faces.
#[derive(Debug, Clone, PartialEq)]
pub enum Diagnostic {
    /// No triangle maps to the face.
    Empty { face: String },
    /// The chart has several connected components.
    Components { face: String, count: usize },
    /// The chart's Euler characteristic differs from the face's.
    Euler { face: String, euler: i64, expected: i64 },
    /// Two faces share an edge but their charts do not meet.
    MissingAdjacency { a: String, b: String },
    /// Two charts meet but their faces share no edge.
    ExtraAdjacency { a: String, b: String },
    /// No input vertex where the charts of the corner's faces meet.
    MissingCorner { corner: usize, faces: String },
    /// Several input vertices where the charts of the corner's faces meet.
    AmbiguousCorner { corner: usize, faces: String, count: usize },
}

impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Diagnostic::Empty { face } => write!(f, "face {face} has no chart (no triangle maps to it)"),
            Diagnostic::Components { face, count } => write!(f, "chart of face {face} has {count} components"),
            Diagnostic::Euler { face, euler, expected } => {
                let what = if *expected == 1 { "not a disc" } else { "not of the face's topology" };
                write!(f, "chart of face {face} is {what} (Euler characteristic {euler}, the face has {expected})")
            }
            Diagnostic::MissingAdjacency { a, b } => write!(f, "charts of faces {a} and {b} do not meet but the faces share an edge"),
            Diagnostic::ExtraAdjacency { a, b } => write!(f, "charts of faces {a} and {b} meet but the faces share no edge"),
            Diagnostic::MissingCorner { corner, faces } => write!(f, "corner {corner} ({faces}): no input vertex where these charts meet"),
            Diagnostic::AmbiguousCorner { corner, faces, count } => {
                write!(f, "corner {corner} ({faces}): the charts meet at {count} input vertices")
            }
        }
    }
}

/// The topology of a labelling: per-chart stats, the corner vertices and what does not match.
#[derive(Debug, Clone, Default)]
pub struct ChartTopology {
    pub charts: Vec<ChartStats>,
    /// Per polycube corner: the input vertex where the charts of its faces meet.
    pub corners: Vec<Option<u32>>,
    /// Pairs of charts that meet (smaller face id first).
    pub adjacency: BTreeSet<(usize, usize)>,
    pub diagnostics: Vec<Diagnostic>,
}

/// Check a labelling against the polycube (see the module docs).
pub fn check_topology(mesh: &TriMesh, g: &TriGraph, pf: &PolycubeFaces, labels: &[u32]) -> ChartTopology {
    let nf = pf.faces.len();
    let mut out = ChartTopology { charts: vec![ChartStats::default(); nf], ..Default::default() };
    for (f, st) in out.charts.iter_mut().enumerate() {
        st.expected_euler = 2 - pf.faces[f].loops.len() as i64;
        st.components = components(g, labels, f as u32).len();
    }
    // Euler characteristic per chart: vertices, edges, faces of its triangles
    let mut verts: Vec<BTreeSet<u32>> = vec![BTreeSet::new(); nf];
    let mut edges: Vec<BTreeSet<(u32, u32)>> = vec![BTreeSet::new(); nf];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let f = labels[t] as usize;
        out.charts[f].triangles += 1;
        out.charts[f].area += g.areas[t];
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            verts[f].insert(a);
            edges[f].insert((a.min(b), a.max(b)));
        }
    }
    for f in 0..nf {
        let st = &mut out.charts[f];
        st.euler = verts[f].len() as i64 - edges[f].len() as i64 + st.triangles as i64;
        let name = pf.name(f);
        if st.triangles == 0 {
            out.diagnostics.push(Diagnostic::Empty { face: name });
            continue;
        }
        if st.components > 1 {
            out.diagnostics.push(Diagnostic::Components { face: name.clone(), count: st.components });
        }
        if st.euler != st.expected_euler {
            out.diagnostics.push(Diagnostic::Euler { face: name, euler: st.euler, expected: st.expected_euler });
        }
    }
    for (t, nb) in g.neighbours.iter().enumerate() {
        for &(u, _, _) in nb {
            let (a, b) = (labels[t] as usize, labels[u as usize] as usize);
            if a != b {
                out.adjacency.insert((a.min(b), a.max(b)));
            }
        }
    }
    for &(a, b) in pf.adjacency.difference(&out.adjacency) {
        out.diagnostics.push(Diagnostic::MissingAdjacency { a: pf.name(a), b: pf.name(b) });
    }
    for &(a, b) in out.adjacency.difference(&pf.adjacency) {
        out.diagnostics.push(Diagnostic::ExtraAdjacency { a: pf.name(a), b: pf.name(b) });
    }
    find_corners(mesh, pf, labels, &mut out);
    out
}

/// Corners: input vertices whose incident charts are exactly a polycube corner's faces;
/// where several, the one nearest the corner (reported as ambiguous).
fn find_corners(mesh: &TriMesh, pf: &PolycubeFaces, labels: &[u32], out: &mut ChartTopology) {
    let mut around: StableHashMap<u32, BTreeSet<usize>> = StableHashMap::default();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for &v in tri {
            around.entry(v).or_default().insert(labels[t] as usize);
        }
    }
    let mut by_set: StableHashMap<Vec<usize>, Vec<u32>> = StableHashMap::default();
    for (v, s) in around {
        if s.len() >= 3 {
            by_set.entry(s.into_iter().collect()).or_default().push(v);
        }
    }
    for (c, corner) in pf.corners.iter().enumerate() {
        let names = || corner.faces.iter().map(|&f| pf.name(f)).collect::<Vec<_>>().join(", ");
        match by_set.get(&corner.faces) {
            None => {
                out.corners.push(None);
                out.diagnostics.push(Diagnostic::MissingCorner { corner: c, faces: names() });
            }
            Some(vs) => {
                let d = |v: u32| crate::geometry::vec3::dist2(mesh.vertices[v as usize], corner.position);
                let best = vs.iter().copied().min_by(|&a, &b| d(a).total_cmp(&d(b)).then(a.cmp(&b))).unwrap();
                if vs.len() > 1 {
                    out.diagnostics.push(Diagnostic::AmbiguousCorner { corner: c, faces: names(), count: vs.len() });
                }
                out.corners.push(Some(best));
            }
        }
    }
}
