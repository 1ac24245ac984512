//! TH-spline3D: an unstructured tricubic volumetric spline on the all-hex
//! control mesh, with boundary and sharp-feature rules, a least-squares fit of
//! the boundary to the input surface, truncated hierarchical local refinement
//! and Bézier extraction (issue 7). See docs/spline.md for the construction, the
//! conventions and every default.
//!
//! The representation is the Bézier extraction itself: each (leaf) element
//! stores the ids of the basis functions that do not vanish on it and the
//! extraction operator C (one row per basis function, 64 columns for the
//! Bernstein polynomials, index i + 4j + 16k with u fastest); the restriction of
//! basis function `ids[r]` to the element is `sum_k C[r][k] B_k(u, v, w)`. Every
//! basis function has a control point with weight 1 (polynomial spline).

pub mod bernstein;
pub mod check;
mod construct;
pub mod fit;
pub mod iga;
pub mod nodes;
mod refine;
pub mod topology;

use crate::error::{check_progress, Error, Progress, Result};
use crate::hex::HexMesh;
use crate::mesh::TriMesh;
use bernstein::NB;
use nodes::{NodeKey, LMAX, R};
use serde::{Deserialize, Serialize};
use std::time::Instant;
use topology::Topology;

pub use fit::{FitOptions, SurfaceDistance};
pub use refine::{RefineOptions, RefineReport};

/// How the spline is built. Every field has a documented default (see `Default`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SplineOptions {
    /// A boundary edge is sharp when the normals of its two boundary quads
    /// differ by more than this angle, in degrees (default 60); boundary edges of
    /// a single element (two boundary faces of one hex) are always sharp. Sharp edges get
    /// the curve rule (C0 across them, the edge curve follows its vertices) and
    /// vertices where three or more sharp edges meet, or where a sharp curve turns
    /// by more than this angle, are interpolated. `None` turns detection off.
    pub sharp_angle_deg: Option<f64>,
    /// Extra sharp edges given by their two control-mesh vertex ids (default
    /// empty). They must be boundary edges.
    pub sharp_edges: Vec<[u32; 2]>,
    /// Add Bernstein (C0) basis functions on the two Bézier layers next to the
    /// boundary of every boundary element (default false). Without it the spline
    /// is C2 up to a flat boundary with the "natural" end condition, which limits
    /// the L2 convergence of analyses whose solution has a non-zero second normal
    /// derivative at the boundary; with it the approximation order is the full
    /// tricubic one near the boundary, at the cost of more basis functions.
    pub boundary_enrichment: bool,
    /// Choose the control points of the vertex functions so that the spline
    /// passes through every control-mesh vertex (the corner Bézier point of each
    /// vertex equals the vertex; one sparse LU solve). Default false: on
    /// HexGen's joint it creates more inverted Gauss points than it removes
    /// (ringing across graded layers; see BENCHMARKS.md). With false the control
    /// points are the hex vertices.
    pub interpolate_vertices: bool,
    /// Repair elements whose Jacobian is not positive at some 3x3x3 Gauss point
    /// or 5x5x5 lattice point (corners included):
    /// their 64 Bézier nodes become Bernstein functions placed on the control-mesh
    /// element's trilinear map (C0 there), repeated while neighbours go bad
    /// (default true). The spline is then valid wherever the hex mesh is.
    pub repair_jacobian: bool,
    /// Fit the spline boundary to the surface given to `build_spline` (default
    /// true; nothing happens without a surface).
    pub fit: FitOptions,
    /// Automatic local refinement after the first fit, where the boundary is
    /// farthest from the surface (default: none). Needs a surface.
    pub refine: Option<RefineOptions>,
    /// Write sparse operator rows in BEXT (default true: each row lists its
    /// non-zero entries with their Bernstein index, a fraction of the dense rows'
    /// size; false: dense rows of 64 entries, as Hex2Spline writes them by default;
    /// the command line's `--dense-bext`).
    pub sparse_bext: bool,
    /// Absolute tolerance of the BEXT operator entries the run folder writes: each
    /// entry is written with the fewest decimals that read back within it (default
    /// [`DEFAULT_BEXT_TOLERANCE`], 1e-8; 0: every entry exact,
    /// the shortest text of its f64; the command line's `--bext-tolerance`).
    pub bext_tolerance: f64,
}

/// The default absolute tolerance of the operator entries in the run folder's
/// spline.bext ([`SplineOptions::bext_tolerance`]): 1e-8, so each entry (a value in
/// [0, 1]) is written with at most 8 decimals and reads back within 1e-8 of the
/// computed one. A Bézier point `Pb[k] = sum_r C[r][k] P[r]` then moves by at most
/// 1e-8 times the sum of `|P[r]|` over the element's functions (some 60 of them:
/// below 1e-6 times the part's largest coordinate, orders below the spline's fit
/// to the surface), and the file is about half the exact form's size (the torus of
/// the test meshes: 34 MB sparse against 63 MB dense and exact).
pub const DEFAULT_BEXT_TOLERANCE: f64 = 1e-8;

impl Default for SplineOptions {
    fn default() -> Self {
        SplineOptions {
            sharp_angle_deg: Some(60.0),
            sharp_edges: Vec::new(),
            boundary_enrichment: false,
            interpolate_vertices: false,
            repair_jacobian: true,
            fit: FitOptions::default(),
            refine: None,
            sparse_bext: true,
            bext_tolerance: DEFAULT_BEXT_TOLERANCE,
        }
    }
}

/// What a basis function is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BasisKind {
    /// The level-0 function of a control-mesh vertex (possibly truncated).
    Vertex(u32),
    /// A Bernstein function of a Bézier node of the given level (boundary
    /// enrichment at level 0, local refinement at levels >= 1).
    Bernstein { level: u8, key: NodeKey },
}

/// Extraction operator of one element in compressed rows.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SparseOp {
    ptr: Vec<u32>,
    col: Vec<u8>,
    val: Vec<f64>,
}

impl SparseOp {
    /// From a dense row-major `rows x 64` matrix (exact zeros are dropped).
    pub fn from_dense(d: &[f64], rows: usize) -> SparseOp {
        let mut op = SparseOp { ptr: Vec::with_capacity(rows + 1), col: Vec::new(), val: Vec::new() };
        op.ptr.push(0);
        for r in 0..rows {
            for k in 0..NB {
                let v = d[r * NB + k];
                if v != 0.0 {
                    op.col.push(k as u8);
                    op.val.push(v);
                }
            }
            op.ptr.push(op.col.len() as u32);
        }
        op
    }

    pub fn rows(&self) -> usize {
        self.ptr.len().saturating_sub(1)
    }

    pub fn row(&self, r: usize) -> (&[u8], &[f64]) {
        let (a, b) = (self.ptr[r] as usize, self.ptr[r + 1] as usize);
        (&self.col[a..b], &self.val[a..b])
    }

    pub fn to_dense(&self) -> Vec<f64> {
        let mut d = vec![0.0; self.rows() * NB];
        for r in 0..self.rows() {
            let (c, v) = self.row(r);
            for (&k, &x) in c.iter().zip(v) {
                d[r * NB + k as usize] = x;
            }
        }
        d
    }

    pub fn nnz(&self) -> usize {
        self.val.len()
    }
}

/// A (leaf) element: a box of a root (control-mesh) element.
#[derive(Debug, Clone)]
pub struct Element {
    /// Control-mesh element it lies in.
    pub root: u32,
    /// Refinement level (0 = the control-mesh element itself).
    pub level: u8,
    /// Integer origin at its level: the element spans
    /// `[origin/2^level, (origin+1)/2^level]` of the root's parameter cube.
    pub origin: [u32; 3],
    basis: Vec<u32>,
    op: SparseOp,
}

impl Element {
    /// Grid units (see `nodes::R`) per Bézier step of this element.
    fn step(&self) -> u32 {
        1 << (LMAX - self.level)
    }

    /// Integer position (root grid units) of Bézier node n.
    fn node_pos(&self, n: usize) -> [u32; 3] {
        let ijk = bernstein::bijk(n);
        let s = self.step();
        [0, 1, 2].map(|d| (self.origin[d] * 3 + ijk[d] as u32) * s)
    }

    /// Does the element's closed box contain the position p (root grid units)?
    fn contains(&self, p: [u32; 3]) -> bool {
        let size = 3 * self.step();
        (0..3).all(|d| p[d] >= self.origin[d] * size && p[d] <= (self.origin[d] + 1) * size)
    }

    /// Bernstein index of position p if it is a node of this element.
    fn node_at(&self, p: [u32; 3]) -> Option<usize> {
        if !self.contains(p) {
            return None;
        }
        let s = self.step();
        let mut ijk = [0usize; 3];
        for d in 0..3 {
            let off = p[d] - self.origin[d] * 3 * s;
            if off % s != 0 {
                return None;
            }
            ijk[d] = (off / s) as usize;
        }
        Some(bernstein::bidx(ijk[0], ijk[1], ijk[2]))
    }

    pub fn basis(&self) -> &[u32] {
        &self.basis
    }
}

/// Seconds spent in the stages of `build_spline`.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SplineSeconds {
    pub construction: f64,
    pub fitting: f64,
    pub refinement: f64,
    pub check: f64,
}

/// Summary of a spline, for report.json (`spline` key) and BENCHMARKS.md.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SplineReport {
    pub elements: usize,
    pub basis_functions: usize,
    pub control_mesh_vertices: usize,
    pub control_mesh_elements: usize,
    pub max_level: u8,
    /// Interior edges of valence other than 4.
    pub extraordinary_edges: usize,
    pub sharp_edges: usize,
    pub boundary_faces: usize,
    /// Basis functions that are Bernstein functions (enrichment and refinement).
    pub bernstein_functions: usize,
    /// Non-zeros of all extraction operators.
    pub operator_nonzeros: usize,
    /// Minimum Jacobian determinant of the spline map at the 3x3x3 Gauss points
    /// of every element (element parameters in [0,1]^3).
    pub min_jacobian: f64,
    /// Minimum over those Gauss points of det J / (|J e1| |J e2| |J e3|).
    pub min_scaled_jacobian: f64,
    pub mean_scaled_jacobian: f64,
    /// Elements with a Gauss point where det J <= 0.
    pub negative_jacobian_elements: usize,
    /// Distance from the spline boundary to the surface before the fit (None without surface).
    pub fitting_before: Option<SurfaceDistance>,
    /// ... after the fit (and after automatic refinement when asked).
    pub fitting_after: Option<SurfaceDistance>,
    /// Elements refined automatically.
    pub refined_elements: usize,
    /// Elements replaced by their trilinear control-mesh map because the
    /// spline's Jacobian was not positive there (`SplineOptions::repair_jacobian`).
    pub repaired_elements: usize,
    pub seconds: SplineSeconds,
}

/// A TH-spline3D volumetric spline with its Bézier extraction.
#[derive(Debug, Clone)]
pub struct Spline {
    topo: Topology,
    root_nodes: Vec<[f64; 3]>,
    elems: Vec<Element>,
    ctrl: Vec<[f64; 3]>,
    kinds: Vec<BasisKind>,
    report: SplineReport,
    opts: SplineOptions,
}

/// Build the spline of a hex control mesh. With a surface and `opts.fit.enabled`
/// the boundary control points are fitted to it; with `opts.refine` boundary
/// elements are refined where the distance is largest and fitted again.
pub fn build_spline(
    hex: &HexMesh,
    surface: Option<&TriMesh>,
    opts: &SplineOptions,
    progress: &mut dyn Progress,
) -> Result<Spline> {
    if let Some(a) = opts.sharp_angle_deg {
        if !(a.is_finite() && (0.0..=180.0).contains(&a)) {
            return Err(Error::InvalidArgument(format!("sharp_angle_deg must be in [0, 180], got {a}")));
        }
    }
    check_progress(progress, 0.0, "spline: topology")?;
    let t0 = Instant::now();
    let mut sp = Spline::construct(hex, opts)?;
    sp.report.seconds.construction = t0.elapsed().as_secs_f64();
    check_progress(progress, 0.3, "spline: construction")?;
    if let Some(surf) = surface {
        if surf.triangles.is_empty() {
            return Err(Error::InvalidArgument("the target surface has no triangles".into()));
        }
        let t1 = Instant::now();
        let loc = crate::geometry::SurfaceLocator::new(surf);
        sp.report.fitting_before = Some(fit::surface_distance(&sp, &loc, surf, opts.fit.samples));
        if opts.fit.enabled {
            fit::fit_boundary_with(&mut sp, &loc, surf, &opts.fit)?;
        }
        sp.report.seconds.fitting = t1.elapsed().as_secs_f64();
        check_progress(progress, 0.6, "spline: boundary fit")?;
        if let Some(ro) = &opts.refine {
            let t2 = Instant::now();
            let rr = refine::refine_auto_with(&mut sp, surf, &loc, ro, &opts.fit)?;
            sp.report.refined_elements = rr.refined;
            sp.report.seconds.refinement = t2.elapsed().as_secs_f64();
            check_progress(progress, 0.8, "spline: refinement")?;
        }
        sp.report.fitting_after = Some(fit::surface_distance(&sp, &loc, surf, opts.fit.samples));
    }
    let t3 = Instant::now();
    sp.update_report();
    sp.report.seconds.check = t3.elapsed().as_secs_f64();
    check_progress(progress, 1.0, "spline: done")?;
    Ok(sp)
}

impl Spline {
    /// Level-0 construction (no fitting, no refinement).
    pub fn construct(hex: &HexMesh, opts: &SplineOptions) -> Result<Spline> {
        let topo = Topology::new(hex, opts.sharp_angle_deg, &opts.sharp_edges)?;
        let ops: Vec<(Vec<u32>, SparseOp)> = {
            use rayon::prelude::*;
            (0..topo.ne as u32).into_par_iter().map(|e| construct::element_operator(&topo, e)).collect()
        };
        // compact vertex ids to basis ids (identity when every vertex is used)
        let mut used = vec![false; topo.nv];
        for (ids, _) in &ops {
            for &v in ids {
                used[v as usize] = true;
            }
        }
        let mut map = vec![u32::MAX; topo.nv];
        let mut kinds = Vec::new();
        let mut ctrl = Vec::new();
        for v in 0..topo.nv {
            if used[v] {
                map[v] = kinds.len() as u32;
                kinds.push(BasisKind::Vertex(v as u32));
                ctrl.push(hex.nodes[v]);
            }
        }
        let elems = ops
            .into_iter()
            .enumerate()
            .map(|(e, (ids, op))| Element {
                root: e as u32,
                level: 0,
                origin: [0, 0, 0],
                basis: ids.iter().map(|&v| map[v as usize]).collect(),
                op,
            })
            .collect();
        let mut sp = Spline {
            topo,
            root_nodes: hex.nodes.clone(),
            elems,
            ctrl,
            kinds,
            report: SplineReport::default(),
            opts: opts.clone(),
        };
        if opts.interpolate_vertices {
            sp.interpolate_vertices()?;
        }
        if opts.boundary_enrichment {
            refine::enrich_boundary(&mut sp);
            // on very thin meshes (fewer than 3 element layers) the truncated
            // vertex functions can become dependent; check when it is cheap
            if sp.ctrl.len() <= 4000 {
                let (rank, n) = check::independence_rank(&sp);
                if rank < n {
                    return Err(Error::SplineFailed(format!(
                        "boundary enrichment made the basis linearly dependent (rank {rank} of {n}); \
                         the mesh is too thin for it (use at least 3 element layers) or turn it off"
                    )));
                }
            }
        }
        if opts.repair_jacobian {
            sp.report.repaired_elements = refine::repair_jacobian(&mut sp);
        }
        sp.update_report();
        Ok(sp)
    }

    /// Solve for the vertex control points so that each control-mesh vertex is
    /// the spline's value at that vertex (level-0 spline, before enrichment).
    fn interpolate_vertices(&mut self) -> Result<()> {
        use faer::linalg::solvers::Solve;
        use faer::sparse::{SparseColMat, Triplet};
        let n = self.ctrl.len();
        let mut row_of = vec![u32::MAX; n];
        let mut trip: Vec<Triplet<usize, usize, f64>> = Vec::new();
        let mut rhs = faer::Mat::<f64>::zeros(n, 3);
        for el in &self.elems {
            let corners = self.topo.elements[el.root as usize];
            for (c, &v) in corners.iter().enumerate() {
                // basis id of vertex v
                let Some(bi) = el.basis.iter().position(|&b| self.kinds[b as usize] == BasisKind::Vertex(v)) else {
                    continue;
                };
                let row = el.basis[bi] as usize;
                if row_of[row] != u32::MAX {
                    continue;
                }
                row_of[row] = 1;
                let bits = topology::BITS_OF_VTK[c];
                let k = bernstein::bidx(3 * bits[0], 3 * bits[1], 3 * bits[2]);
                for r in 0..el.op.rows() {
                    let (cols, vals) = el.op.row(r);
                    if let Some(p) = cols.iter().position(|&x| x as usize == k) {
                        trip.push(Triplet::new(row, el.basis[r] as usize, vals[p]));
                    }
                }
                let x = self.root_nodes[v as usize];
                for j in 0..3 {
                    rhs[(row, j)] = x[j];
                }
            }
        }
        if row_of.iter().any(|&r| r == u32::MAX) {
            return Err(Error::SplineFailed("interpolation: a vertex function has no corner".into()));
        }
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trip)
            .map_err(|e| Error::SplineFailed(format!("interpolation matrix: {e:?}")))?;
        let lu = a.sp_lu().map_err(|e| Error::SplineFailed(format!("interpolation factorisation: {e:?}")))?;
        lu.solve_in_place(rhs.as_mut());
        let mut pts = Vec::with_capacity(n);
        for i in 0..n {
            let p = [rhs[(i, 0)], rhs[(i, 1)], rhs[(i, 2)]];
            if !p.iter().all(|c| c.is_finite()) {
                return Err(Error::SplineFailed("interpolation produced non-finite control points".into()));
            }
            pts.push(p);
        }
        self.ctrl = pts;
        Ok(())
    }

    pub fn num_elements(&self) -> usize {
        self.elems.len()
    }

    pub fn num_basis(&self) -> usize {
        self.ctrl.len()
    }

    /// Control points (one per basis function).
    pub fn control_points(&self) -> &[[f64; 3]] {
        &self.ctrl
    }

    /// Replace the control points (same count); the report is not updated.
    pub fn set_control_points(&mut self, pts: Vec<[f64; 3]>) -> Result<()> {
        if pts.len() != self.ctrl.len() {
            return Err(Error::InvalidArgument(format!(
                "expected {} control points, got {}",
                self.ctrl.len(),
                pts.len()
            )));
        }
        if pts.iter().any(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(Error::InvalidArgument("non-finite control point".into()));
        }
        self.ctrl = pts;
        Ok(())
    }

    /// Weights of the control points (all 1: the spline is polynomial).
    pub fn weights(&self) -> Vec<f64> {
        vec![1.0; self.ctrl.len()]
    }

    pub fn basis_kind(&self, i: usize) -> BasisKind {
        self.kinds[i]
    }

    pub fn elements(&self) -> &[Element] {
        &self.elems
    }

    pub fn element(&self, e: usize) -> Result<&Element> {
        self.elems.get(e).ok_or_else(|| {
            Error::InvalidArgument(format!("element {e} out of range (the spline has {})", self.elems.len()))
        })
    }

    /// Global basis ids of element e (rows of its extraction operator).
    pub fn element_basis(&self, e: usize) -> Result<&[u32]> {
        Ok(&self.element(e)?.basis)
    }

    /// Extraction operator of element e, dense, row-major `n x 64`.
    pub fn extraction_operator(&self, e: usize) -> Result<Vec<f64>> {
        Ok(self.element(e)?.op.to_dense())
    }

    /// Sparse extraction operator of element e.
    pub fn extraction_operator_sparse(&self, e: usize) -> Result<&SparseOp> {
        Ok(&self.element(e)?.op)
    }

    /// The 64 Bézier control points of element e: Pb[k] = sum_r C[r][k] P[ids[r]].
    pub fn bezier_points(&self, e: usize) -> Result<Vec<[f64; 3]>> {
        let el = self.element(e)?;
        Ok(self.bezier_points_of(el))
    }

    fn bezier_points_of(&self, el: &Element) -> Vec<[f64; 3]> {
        let mut pb = vec![[0.0; 3]; NB];
        for r in 0..el.op.rows() {
            let p = self.ctrl[el.basis[r] as usize];
            let (c, v) = el.op.row(r);
            for (&k, &x) in c.iter().zip(v) {
                let q = &mut pb[k as usize];
                q[0] += x * p[0];
                q[1] += x * p[1];
                q[2] += x * p[2];
            }
        }
        pb
    }

    fn check_uvw(e: usize, u: f64, v: f64, w: f64) -> Result<()> {
        for (n, x) in [("u", u), ("v", v), ("w", w)] {
            if !(x.is_finite() && (-1e-12..=1.0 + 1e-12).contains(&x)) {
                return Err(Error::InvalidArgument(format!(
                    "parameter {n} = {x} of element {e} is outside [0, 1]"
                )));
            }
        }
        Ok(())
    }

    /// The spline map and its Jacobian at (u, v, w) in [0,1]^3 of element e.
    /// `jac[i][j] = d x_i / d xi_j` (xi = (u, v, w) of the element).
    pub fn evaluate(&self, e: usize, u: f64, v: f64, w: f64) -> Result<([f64; 3], [[f64; 3]; 3])> {
        Self::check_uvw(e, u, v, w)?;
        let el = self.element(e)?;
        let pb = self.bezier_points_of(el);
        Ok(map_from_bezier(&pb, [u, v, w]))
    }

    /// Values of the element's basis functions at (u, v, w): (ids, values).
    pub fn basis_values(&self, e: usize, u: f64, v: f64, w: f64) -> Result<(Vec<u32>, Vec<f64>)> {
        Self::check_uvw(e, u, v, w)?;
        let el = self.element(e)?;
        let b = bernstein::values([u, v, w]);
        Ok((el.basis.clone(), apply_rows(&el.op, &b)))
    }

    /// Values and parametric gradients (d/du, d/dv, d/dw) of the element's basis
    /// functions at (u, v, w).
    pub fn basis_gradients(&self, e: usize, u: f64, v: f64, w: f64) -> Result<(Vec<u32>, Vec<f64>, Vec<[f64; 3]>)> {
        Self::check_uvw(e, u, v, w)?;
        let el = self.element(e)?;
        let (b, g) = bernstein::values_and_gradients([u, v, w]);
        let vals = apply_rows(&el.op, &b);
        let mut grads = vec![[0.0; 3]; el.op.rows()];
        for (r, gr) in grads.iter_mut().enumerate() {
            let (c, v) = el.op.row(r);
            for (&k, &x) in c.iter().zip(v) {
                for d in 0..3 {
                    gr[d] += x * g[k as usize][d];
                }
            }
        }
        Ok((el.basis.clone(), vals, grads))
    }

    pub fn report(&self) -> &SplineReport {
        &self.report
    }

    pub fn options(&self) -> &SplineOptions {
        &self.opts
    }

    pub fn topology(&self) -> &Topology {
        &self.topo
    }

    /// Control-mesh node positions as given.
    pub fn control_mesh_nodes(&self) -> &[[f64; 3]] {
        &self.root_nodes
    }

    /// The control mesh with the current control points of its vertex functions
    /// (vertices whose function was truncated away keep their input position).
    pub fn control_mesh(&self) -> HexMesh {
        let mut nodes = self.root_nodes.clone();
        for (i, k) in self.kinds.iter().enumerate() {
            if let BasisKind::Vertex(v) = k {
                nodes[*v as usize] = self.ctrl[i];
            }
        }
        HexMesh { nodes, elements: self.topo.elements.clone() }
    }

    /// Leaf element e as (root element, lower corner, upper corner) in the root's
    /// parameters.
    pub fn element_box(&self, e: usize) -> Result<(u32, [f64; 3], [f64; 3])> {
        let el = self.element(e)?;
        let h = 1.0 / (1u32 << el.level) as f64;
        let lo = el.origin.map(|o| o as f64 * h);
        Ok((el.root, lo, lo.map(|x| x + h)))
    }

    /// Recompute the counts and the Gauss-point Jacobian measures of the report.
    pub fn update_report(&mut self) {
        let q = check::gauss_jacobians(self, 3);
        let r = &mut self.report;
        r.elements = self.elems.len();
        r.basis_functions = self.ctrl.len();
        r.control_mesh_vertices = self.topo.nv;
        r.control_mesh_elements = self.topo.ne;
        r.max_level = self.elems.iter().map(|e| e.level).max().unwrap_or(0);
        r.extraordinary_edges = self.topo.extraordinary_edge_count();
        r.sharp_edges = self.topo.sharp_edge_count();
        r.boundary_faces = self.topo.bquads.len();
        r.bernstein_functions = self.kinds.iter().filter(|k| matches!(k, BasisKind::Bernstein { .. })).count();
        r.operator_nonzeros = self.elems.iter().map(|e| e.op.nnz()).sum();
        r.min_jacobian = q.min_det;
        r.min_scaled_jacobian = q.min_scaled;
        r.mean_scaled_jacobian = q.mean_scaled;
        r.negative_jacobian_elements = q.negative_elements;
    }

    /// Remove basis functions that vanish everywhere and renumber.
    fn compact(&mut self) {
        let mut used = vec![false; self.ctrl.len()];
        for el in &self.elems {
            for &b in &el.basis {
                used[b as usize] = true;
            }
        }
        if used.iter().all(|&u| u) {
            return;
        }
        let mut map = vec![u32::MAX; used.len()];
        let mut ctrl = Vec::new();
        let mut kinds = Vec::new();
        for i in 0..used.len() {
            if used[i] {
                map[i] = ctrl.len() as u32;
                ctrl.push(self.ctrl[i]);
                kinds.push(self.kinds[i]);
            }
        }
        for el in &mut self.elems {
            for b in &mut el.basis {
                *b = map[*b as usize];
            }
        }
        self.ctrl = ctrl;
        self.kinds = kinds;
    }

    /// Position in root grid units of Bézier node n of element e (used by tests).
    pub fn node_key(&self, e: usize, n: usize) -> Result<NodeKey> {
        let el = self.element(e)?;
        if n >= NB {
            return Err(Error::InvalidArgument(format!("Bézier node {n} out of range")));
        }
        Ok(nodes::key_of(&self.topo, el.root, el.node_pos(n)))
    }
}

/// Rows of `op` applied to a vector of 64 Bernstein values.
pub(crate) fn apply_rows(op: &SparseOp, b: &[f64; NB]) -> Vec<f64> {
    (0..op.rows())
        .map(|r| {
            let (c, v) = op.row(r);
            c.iter().zip(v).map(|(&k, &x)| x * b[k as usize]).sum()
        })
        .collect()
}

/// Point and Jacobian of a tricubic Bézier volume at p.
pub fn map_from_bezier(pb: &[[f64; 3]], p: [f64; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let (b, g) = bernstein::values_and_gradients(p);
    let mut x = [0.0; 3];
    let mut j = [[0.0; 3]; 3];
    for k in 0..NB {
        for i in 0..3 {
            x[i] += b[k] * pb[k][i];
            for d in 0..3 {
                j[i][d] += g[k][d] * pb[k][i];
            }
        }
    }
    (x, j)
}

/// Determinant of a 3x3 matrix.
pub fn det3(j: &[[f64; 3]; 3]) -> f64 {
    j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1]) - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
        + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0])
}

/// det J / product of the column lengths (1 for an orthogonal frame).
pub fn scaled_det(j: &[[f64; 3]; 3]) -> f64 {
    let col = |d: usize| (j[0][d] * j[0][d] + j[1][d] * j[1][d] + j[2][d] * j[2][d]).sqrt();
    let l = col(0) * col(1) * col(2);
    if l <= f64::MIN_POSITIVE {
        return -1.0;
    }
    det3(j) / l
}

#[allow(dead_code)]
const _: () = assert!(R % 8 == 0);
