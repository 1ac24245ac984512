//! TH-spline3D: an unstructured tricubic volumetric spline on the all-hex
//! control mesh, with boundary and sharp-feature rules, a least-squares fit of
//! the boundary to the input surface, truncated hierarchical local refinement
//! and Bézier extraction. See docs/spline.md for the construction, the
//! conventions and every default.
//!
//! The representation is the Bézier extraction itself: each (leaf) element
//! stores the ids of the basis functions that do not vanish on it and the
//! extraction operator C (one row per basis function, 64 columns for the
//! Bernstein polynomials, index i + 4j + 16k with u fastest); the restriction of
//! basis function `ids[r]` to the element is `sum_k C[r][k] B_k(u, v, w)`. Every
//! basis function has a control point with weight 1 (polynomial spline).

pub mod bernstein;
mod build;
pub mod check;
mod construct;
mod evaluate;
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
pub use evaluate::{det3, map_from_bezier, scaled_det};
pub(crate) use evaluate::apply_rows;

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
    /// Interior faces between unrefined elements across which the spline is C2:
    /// every basis function's second normal derivative agrees on both sides at
    /// 2 x 2 points of the face ([`check::continuity`]). The spline drops to C1 / C0
    /// next to irregular edges and sharp features, so this share measures how much
    /// of the mesh the regular structure carries.
    pub c2_faces: usize,
    /// Interior faces between unrefined elements that were measured.
    pub interior_faces: usize,
    /// `c2_faces / interior_faces` (0 without interior face).
    pub c2_face_share: f64,
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
    sp.update_continuity();
    sp.report.seconds.check = t3.elapsed().as_secs_f64();
    check_progress(progress, 1.0, "spline: done")?;
    Ok(sp)
}

#[allow(dead_code)]
const _: () = assert!(R % 8 == 0);
