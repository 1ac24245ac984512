//! Topology of the level-0 control mesh: faces, edges, vertex stars, the
//! boundary quadrilaterals with outward orientation, sharp boundary edges and
//! the classification of extraordinary entities.

use crate::error::{Error, Result};
use crate::geometry::vec3::{add, cross, dot, norm, scale, sub};
use crate::hex::HexMesh;
use std::collections::HashMap;

/// VTK node index of the corner with parametric bits (x, y, z).
pub const VTK_OF_BITS: [usize; 8] = [0, 1, 3, 2, 4, 5, 7, 6];
/// Parametric bits (x, y, z) of VTK node n.
pub const BITS_OF_VTK: [[usize; 3]; 8] =
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]];

#[inline]
pub fn vtk_of_bits(b: [usize; 3]) -> usize {
    VTK_OF_BITS[b[0] + 2 * b[1] + 4 * b[2]]
}

/// The two directions other than `d`, in increasing order.
#[inline]
pub fn other_dims(d: usize) -> [usize; 2] {
    match d {
        0 => [1, 2],
        1 => [0, 2],
        _ => [0, 1],
    }
}

/// Corners of local face (dim d, side s) in cyclic order: (0,0), (1,0), (1,1), (0,1)
/// in the bits of the two other directions. Returns VTK node indices.
pub fn face_corners_local(d: usize, s: usize) -> [usize; 4] {
    let [d1, d2] = other_dims(d);
    let mk = |b1: usize, b2: usize| {
        let mut b = [0usize; 3];
        b[d] = s;
        b[d1] = b1;
        b[d2] = b2;
        vtk_of_bits(b)
    };
    [mk(0, 0), mk(1, 0), mk(1, 1), mk(0, 1)]
}

/// Local edge index: free direction d, bits (b1, b2) of the other two directions.
#[inline]
pub fn edge_local(d: usize, b1: usize, b2: usize) -> usize {
    d * 4 + b1 + 2 * b2
}

#[derive(Debug, Clone)]
pub struct Face {
    /// Vertex ids sorted (the key).
    pub key: [u32; 4],
    /// (element, dim, side) of each element having this face (1 or 2).
    pub elems: Vec<(u32, u8, u8)>,
}

#[derive(Debug, Clone)]
pub struct Edge {
    pub v: [u32; 2],
    pub elems: Vec<u32>,
    /// Boundary quads (indices into `Topology::bquads`) containing this edge.
    pub bquads: Vec<u32>,
    pub sharp: bool,
}

impl Edge {
    pub fn is_boundary(&self) -> bool {
        !self.bquads.is_empty()
    }
}

/// A boundary face with its corners in an outward (counter-clockwise seen from
/// outside) cyclic order.
#[derive(Debug, Clone)]
pub struct BQuad {
    pub elem: u32,
    pub dim: u8,
    pub side: u8,
    pub corners: [u32; 4],
    pub normal: [f64; 3],
}

impl BQuad {
    /// Weights of the quad "body point" next to corner v (bilinear 2/3, 1/3).
    pub fn body_weights(&self, v: u32) -> [(u32, f64); 4] {
        let m = self.corners.iter().position(|&c| c == v).expect("vertex of quad");
        [
            (self.corners[m], 4.0 / 9.0),
            (self.corners[(m + 1) % 4], 2.0 / 9.0),
            (self.corners[(m + 3) % 4], 2.0 / 9.0),
            (self.corners[(m + 2) % 4], 1.0 / 9.0),
        ]
    }
}

/// How a boundary vertex is treated by the boundary rules.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VertexKind {
    Interior,
    /// On a smooth part of the boundary (no sharp edge).
    Smooth,
    /// On a sharp curve passing straight-ish through: the two neighbours along it.
    Crease(u32, u32),
    /// Interpolated: curve end, curve corner, or meeting of three or more sharp edges.
    Corner,
}

#[derive(Debug, Clone)]
pub struct Topology {
    pub nv: usize,
    /// The control mesh's elements (VTK node order).
    pub elements: Vec<[u32; 8]>,
    pub ne: usize,
    pub faces: Vec<Face>,
    /// Face index of local face (d, s) of each element: index d*2+s.
    pub elem_faces: Vec<[u32; 6]>,
    pub edges: Vec<Edge>,
    pub edge_index: HashMap<(u32, u32), u32>,
    /// Edge index of local edge of each element (see `edge_local`).
    pub elem_edges: Vec<[u32; 12]>,
    /// Elements around each vertex.
    pub star: Vec<Vec<u32>>,
    /// Edges incident to each vertex.
    pub vertex_edges: Vec<Vec<u32>>,
    pub bquads: Vec<BQuad>,
    /// Boundary quads around each vertex.
    pub vertex_bquads: Vec<Vec<u32>>,
    pub vertex_kind: Vec<VertexKind>,
    /// Face index of each boundary quad.
    pub bquad_face: Vec<u32>,
    /// Boundary quad of each face (u32::MAX for interior faces).
    pub face_bquad: Vec<u32>,
}

fn ekey(a: u32, b: u32) -> (u32, u32) {
    if a < b {
        (a, b)
    } else {
        (b, a)
    }
}

impl Topology {
    /// Build the topology; `sharp_angle_deg` is the normal deviation above which a
    /// boundary edge is sharp (None: no automatic detection); `given` adds sharp edges.
    /// The topology of `hex`: faces, edges, stars, boundary quads, sharp edges
    /// (dihedral angle below `sharp_angle_deg`, plus the `given` ones) and the
    /// vertex kinds, one step a function below.
    pub fn new(hex: &HexMesh, sharp_angle_deg: Option<f64>, given: &[[u32; 2]]) -> Result<Topology> {
        let nv = hex.nodes.len();
        let ne = hex.elements.len();
        validate_hex(hex)?;
        let (faces, elem_faces) = build_faces(hex)?;
        let (mut edges, edge_index, elem_edges) = build_edges(hex);
        let mut star = vec![Vec::new(); nv];
        let mut vertex_edges = vec![Vec::new(); nv];
        for (e, el) in hex.elements.iter().enumerate() {
            for &v in el {
                star[v as usize].push(e as u32);
            }
        }
        for (i, ed) in edges.iter().enumerate() {
            vertex_edges[ed.v[0] as usize].push(i as u32);
            vertex_edges[ed.v[1] as usize].push(i as u32);
        }
        let (bquads, bquad_face, face_bquad, vertex_bquads) = boundary_quads(hex, &faces, &mut edges, &edge_index);
        let cos_limit = sharp_angle_deg.map(|a| a.to_radians().cos());
        mark_sharp_edges(&mut edges, &edge_index, &bquads, cos_limit, given)?;
        let vertex_kind = vertex_kinds(hex, &edges, &vertex_edges, &vertex_bquads, cos_limit);
        Ok(Topology {
            nv,
            elements: hex.elements.clone(),
            ne,
            faces,
            elem_faces,
            edges,
            edge_index,
            elem_edges,
            star,
            vertex_edges,
            bquads,
            vertex_bquads,
            vertex_kind,
            bquad_face,
            face_bquad,
        })
    }

    pub fn edge(&self, a: u32, b: u32) -> Option<&Edge> {
        self.edge_index.get(&ekey(a, b)).map(|&i| &self.edges[i as usize])
    }

    /// An interior edge whose valence is not 4.
    pub fn is_extraordinary_edge(&self, e: &Edge) -> bool {
        !e.is_boundary() && e.elems.len() != 4
    }

    /// Interior vertex whose star is a regular 2x2x2 block: 8 elements, 6 edges,
    /// all of valence 4.
    pub fn is_regular_interior_vertex(&self, v: usize) -> bool {
        self.vertex_kind[v] == VertexKind::Interior
            && self.star[v].len() == 8
            && self.vertex_edges[v].len() == 6
            && self.vertex_edges[v].iter().all(|&e| self.edges[e as usize].elems.len() == 4)
    }

    /// Number of interior edges with valence other than 4.
    pub fn extraordinary_edge_count(&self) -> usize {
        self.edges.iter().filter(|e| self.is_extraordinary_edge(e)).count()
    }

    pub fn sharp_edge_count(&self) -> usize {
        self.edges.iter().filter(|e| e.sharp).count()
    }
}

/// Nodes finite, element indices in range and distinct, at least one element.
fn validate_hex(hex: &HexMesh) -> Result<()> {
    let (nv, ne) = (hex.nodes.len(), hex.elements.len());
    if ne == 0 {
        return Err(Error::InvalidArgument("the hex mesh has no elements".into()));
    }
    for (i, p) in hex.nodes.iter().enumerate() {
        if !p.iter().all(|c| c.is_finite()) {
            return Err(Error::InvalidArgument(format!("hex node {i} has a non-finite coordinate")));
        }
    }
    for (e, el) in hex.elements.iter().enumerate() {
        for (a, &v) in el.iter().enumerate() {
            if v as usize >= nv {
                return Err(Error::InvalidArgument(format!(
                    "hex element {e} refers to node {v} but the mesh has {nv} nodes"
                )));
            }
            if el[..a].contains(&v) {
                return Err(Error::InvalidArgument(format!("hex element {e} repeats node {v}")));
            }
        }
    }
    Ok(())
}

/// The faces (keyed by their sorted corners) and each element's six face ids;
/// a face of more than two elements, or of one element twice, is refused.
fn build_faces(hex: &HexMesh) -> Result<(Vec<Face>, Vec<[u32; 6]>)> {
    let ne = hex.elements.len();
    let mut face_map: HashMap<[u32; 4], u32> = HashMap::new();
    let mut faces: Vec<Face> = Vec::new();
    let mut elem_faces = vec![[0u32; 6]; ne];
    for (e, el) in hex.elements.iter().enumerate() {
        for d in 0..3 {
            for s in 0..2 {
                let lc = face_corners_local(d, s);
                let mut key = lc.map(|c| el[c]);
                key.sort_unstable();
                let id = *face_map.entry(key).or_insert_with(|| {
                    faces.push(Face { key, elems: Vec::new() });
                    (faces.len() - 1) as u32
                });
                faces[id as usize].elems.push((e as u32, d as u8, s as u8));
                elem_faces[e][d * 2 + s] = id;
            }
        }
    }
    for f in &faces {
        if f.elems.len() > 2 {
            return Err(Error::InvalidArgument(format!(
                "hex face {:?} is shared by {} elements (non-manifold)",
                f.key,
                f.elems.len()
            )));
        }
        if f.elems.len() == 2 && f.elems[0].0 == f.elems[1].0 {
            return Err(Error::InvalidArgument(format!("hex element {} is glued to itself", f.elems[0].0)));
        }
    }
    Ok((faces, elem_faces))
}

/// The edges with their elements, the index by end points and each element's
/// twelve edge ids.
fn build_edges(hex: &HexMesh) -> (Vec<Edge>, HashMap<(u32, u32), u32>, Vec<[u32; 12]>) {
    let ne = hex.elements.len();
    let mut edge_index: HashMap<(u32, u32), u32> = HashMap::new();
    let mut edges: Vec<Edge> = Vec::new();
    let mut elem_edges = vec![[0u32; 12]; ne];
    for (e, el) in hex.elements.iter().enumerate() {
        for d in 0..3 {
            let [d1, d2] = other_dims(d);
            for b2 in 0..2 {
                for b1 in 0..2 {
                    let mut lo = [0usize; 3];
                    lo[d1] = b1;
                    lo[d2] = b2;
                    let mut hi = lo;
                    hi[d] = 1;
                    let (a, b) = (el[vtk_of_bits(lo)], el[vtk_of_bits(hi)]);
                    let k = ekey(a, b);
                    let id = *edge_index.entry(k).or_insert_with(|| {
                        edges.push(Edge { v: [k.0, k.1], elems: Vec::new(), bquads: Vec::new(), sharp: false });
                        (edges.len() - 1) as u32
                    });
                    edges[id as usize].elems.push(e as u32);
                    elem_edges[e][edge_local(d, b1, b2)] = id;
                }
            }
        }
    }
    (edges, edge_index, elem_edges)
}

/// Boundary quads oriented outward (away from their element's centre) with their
/// unit normals, the face <-> quad maps, and each boundary edge's and vertex's quads.
#[allow(clippy::type_complexity)]
fn boundary_quads(hex: &HexMesh, faces: &[Face], edges: &mut [Edge], edge_index: &HashMap<(u32, u32), u32>) -> (Vec<BQuad>, Vec<u32>, Vec<u32>, Vec<Vec<u32>>) {
    let nv = hex.nodes.len();
    let mut bquads = Vec::new();
    let mut bquad_face = Vec::new();
    for (fi, f) in faces.iter().enumerate() {
        if f.elems.len() != 1 {
            continue;
        }
        let (e, d, s) = f.elems[0];
        let el = &hex.elements[e as usize];
        let lc = face_corners_local(d as usize, s as usize);
        let mut corners = lc.map(|c| el[c]);
        let p = corners.map(|c| hex.nodes[c as usize]);
        let mut n = cross(sub(p[2], p[0]), sub(p[3], p[1]));
        let fc = scale(add(add(p[0], p[1]), add(p[2], p[3])), 0.25);
        let mut ec = [0.0; 3];
        for &v in el {
            ec = add(ec, hex.nodes[v as usize]);
        }
        ec = scale(ec, 1.0 / 8.0);
        if dot(n, sub(fc, ec)) < 0.0 {
            corners = [corners[0], corners[3], corners[2], corners[1]];
            n = scale(n, -1.0);
        }
        let l = norm(n);
        let normal = if l > 0.0 { scale(n, 1.0 / l) } else { [0.0; 3] };
        bquads.push(BQuad { elem: e, dim: d, side: s, corners, normal });
        bquad_face.push(fi as u32);
    }
    let mut face_bquad = vec![u32::MAX; faces.len()];
    for (q, &f) in bquad_face.iter().enumerate() {
        face_bquad[f as usize] = q as u32;
    }
    let mut vertex_bquads = vec![Vec::new(); nv];
    for (qi, q) in bquads.iter().enumerate() {
        for m in 0..4 {
            let (a, b) = (q.corners[m], q.corners[(m + 1) % 4]);
            let id = edge_index[&ekey(a, b)];
            edges[id as usize].bquads.push(qi as u32);
            vertex_bquads[a as usize].push(qi as u32);
        }
    }
    (bquads, bquad_face, face_bquad, vertex_bquads)
}

/// Sharp edges: boundary edges that are not shared by two boundary quads of
/// different elements, edges whose quads' normals differ by more than the angle
/// (cosine `cos_limit`), and the `given` ones (refused unless boundary edges).
fn mark_sharp_edges(edges: &mut [Edge], edge_index: &HashMap<(u32, u32), u32>, bquads: &[BQuad], cos_limit: Option<f64>, given: &[[u32; 2]]) -> Result<()> {
    for ed in edges.iter_mut() {
        if ed.bquads.is_empty() {
            continue;
        }
        // an edge of a single element with two boundary faces: the element's
        // corner there must survive, whatever the surface does
        if ed.bquads.len() != 2 || ed.elems.len() == 1 {
            ed.sharp = true;
            continue;
        }
        if let Some(cl) = cos_limit {
            let n0 = bquads[ed.bquads[0] as usize].normal;
            let n1 = bquads[ed.bquads[1] as usize].normal;
            if dot(n0, n1) < cl {
                ed.sharp = true;
            }
        }
    }
    for g in given {
        match edge_index.get(&ekey(g[0], g[1])) {
            Some(&id) if edges[id as usize].is_boundary() => edges[id as usize].sharp = true,
            Some(_) => {
                return Err(Error::InvalidArgument(format!(
                    "given sharp edge ({}, {}) is not a boundary edge",
                    g[0], g[1]
                )))
            }
            None => {
                return Err(Error::InvalidArgument(format!(
                    "given sharp edge ({}, {}) is not an edge of the hex mesh",
                    g[0], g[1]
                )))
            }
        }
    }
    Ok(())
}

/// Each vertex's kind from its sharp edges: interior, smooth boundary, crease
/// (two sharp edges meeting straight enough) or corner.
fn vertex_kinds(hex: &HexMesh, edges: &[Edge], vertex_edges: &[Vec<u32>], vertex_bquads: &[Vec<u32>], cos_limit: Option<f64>) -> Vec<VertexKind> {
    let nv = hex.nodes.len();
    let mut vertex_kind = vec![VertexKind::Interior; nv];
    for v in 0..nv {
        if vertex_bquads[v].is_empty() {
            continue;
        }
        let sharp: Vec<u32> = vertex_edges[v]
            .iter()
            .filter(|&&e| edges[e as usize].sharp)
            .map(|&e| {
                let ed = &edges[e as usize];
                if ed.v[0] as usize == v {
                    ed.v[1]
                } else {
                    ed.v[0]
                }
            })
            .collect();
        vertex_kind[v] = match sharp.len() {
            0 => VertexKind::Smooth,
            2 => {
                // straight enough to smooth along the curve?
                let p = hex.nodes[v];
                let a = sub(hex.nodes[sharp[0] as usize], p);
                let b = sub(hex.nodes[sharp[1] as usize], p);
                let c = -dot(a, b) / (norm(a) * norm(b)).max(f64::MIN_POSITIVE);
                match cos_limit {
                    Some(cl) if c < cl => VertexKind::Corner,
                    _ => VertexKind::Crease(sharp[0], sharp[1]),
                }
            }
            _ => VertexKind::Corner,
        };
    }
    vertex_kind
}
