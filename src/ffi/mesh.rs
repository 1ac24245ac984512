//! Mesh handle: load, create from arrays, free, counts, check report, genus, copies.

use super::{ffi_boundary, non_null};
use crate::error::{Error, Result, Status};
use crate::mesh::{LoadOptions, MeshReport, TriMesh, DEFAULT_WELD_TOLERANCE};
use std::ffi::{c_char, CStr};
use std::sync::OnceLock;

/// An opaque mesh handle (create with sddpm_mesh_load or
/// sddpm_mesh_new_from_arrays, release with sddpm_mesh_free). Immutable once
/// created: calls that take it (several pipelines on one mesh included) may come
/// from several threads at once; freeing it while another thread uses it is not allowed.
pub struct SddpmMesh {
    mesh: TriMesh,
    report: OnceLock<MeshReport>,
}

impl SddpmMesh {
    fn report(&self) -> &MeshReport {
        self.report.get_or_init(|| self.mesh.check())
    }
}

/// How a mesh is read; fill with sddpm_load_options_default, then change fields.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct SddpmLoadOptions {
    /// Weld vertices closer than this times the bounding-box diagonal
    /// (default 1e-9; 0 = exact positions only; negative = no welding).
    pub weld_tolerance: f64,
    /// Drop vertices no triangle uses (default true).
    pub remove_unreferenced: bool,
    /// Explicit repair (default false): re-orient a closed manifold consistently outward.
    pub repair_orientation: bool,
}

impl From<SddpmLoadOptions> for LoadOptions {
    fn from(o: SddpmLoadOptions) -> Self {
        LoadOptions {
            weld_tolerance: o.weld_tolerance,
            remove_unreferenced: o.remove_unreferenced,
            repair_orientation: o.repair_orientation,
        }
    }
}

/// What sddpm_mesh_check measured (see docs/mesh-checks.md).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
pub struct SddpmMeshReport {
    pub vertices: usize,
    pub triangles: usize,
    pub edges: usize,
    pub components: usize,
    pub boundary_edges: usize,
    pub boundary_loops: usize,
    pub non_manifold_edges: usize,
    pub non_manifold_vertices: usize,
    pub inconsistent_edges: usize,
    pub collapsed_triangles: usize,
    pub degenerate_triangles: usize,
    pub self_intersecting_pairs: usize,
    pub unreferenced_vertices: usize,
    pub non_finite_vertices: usize,
    pub euler_characteristic: i64,
    /// -1 when undefined (not a closed manifold).
    pub genus: i64,
    pub closed: bool,
    pub manifold: bool,
    pub orientation_consistent: bool,
    pub oriented_outward: bool,
    /// True when the mesh can go on to meshing (sddpm_mesh_validate returns OK).
    pub can_proceed: bool,
    pub volume: f64,
    pub area: f64,
    pub bbox_min: [f64; 3],
    pub bbox_max: [f64; 3],
    pub bbox_diagonal: f64,
}

impl From<&MeshReport> for SddpmMeshReport {
    fn from(r: &MeshReport) -> Self {
        SddpmMeshReport {
            vertices: r.vertices,
            triangles: r.triangles,
            edges: r.edges,
            components: r.components,
            boundary_edges: r.boundary_edges,
            boundary_loops: r.boundary_loops,
            non_manifold_edges: r.non_manifold_edges,
            non_manifold_vertices: r.non_manifold_vertices,
            inconsistent_edges: r.inconsistent_edges,
            collapsed_triangles: r.collapsed_triangles,
            degenerate_triangles: r.degenerate_triangles,
            self_intersecting_pairs: r.self_intersecting_pairs,
            unreferenced_vertices: r.unreferenced_vertices,
            non_finite_vertices: r.non_finite_vertices,
            euler_characteristic: r.euler_characteristic,
            genus: r.genus.unwrap_or(-1),
            closed: r.closed,
            manifold: r.manifold,
            orientation_consistent: r.orientation_consistent,
            oriented_outward: r.oriented_outward,
            can_proceed: r.can_proceed,
            volume: r.volume,
            area: r.area,
            bbox_min: r.bbox_min,
            bbox_max: r.bbox_max,
            bbox_diagonal: r.bbox_diagonal,
        }
    }
}

unsafe fn options(opts: *const SddpmLoadOptions) -> LoadOptions {
    if opts.is_null() {
        LoadOptions::default()
    } else {
        (*opts).into()
    }
}

unsafe fn mesh_ref<'a>(mesh: *const SddpmMesh) -> Result<&'a SddpmMesh> {
    non_null(mesh, "mesh")?;
    Ok(&*mesh)
}

fn new_handle(mesh: TriMesh) -> *mut SddpmMesh {
    Box::into_raw(Box::new(SddpmMesh { mesh, report: OnceLock::new() }))
}

/// Fill `out` with the default load options.
///
/// # Safety
/// `out` must be NULL or point to writable memory for one struct.
#[no_mangle]
pub unsafe extern "C" fn sddpm_load_options_default(out: *mut SddpmLoadOptions) -> Status {
    ffi_boundary! {
        non_null(out, "out")?;
        *out = SddpmLoadOptions { weld_tolerance: DEFAULT_WELD_TOLERANCE, remove_unreferenced: true, repair_orientation: false };
        Ok(())
    }
}

/// Read an OBJ, STL (ASCII or binary) or OFF file (by extension, else by
/// content) and weld it; `opts` may be NULL for the defaults. Unreadable files
/// give IO / PARSE; empty meshes and non-finite coordinates give INVALID_MESH.
/// Whether the surface can go on to meshing is sddpm_mesh_validate's answer.
/// On success `*out` receives a handle to release with sddpm_mesh_free.
///
/// # Safety
/// `path` a NUL-terminated string, `opts` NULL or valid, `out` valid.
#[no_mangle]
pub unsafe extern "C" fn sddpm_mesh_load(path: *const c_char, opts: *const SddpmLoadOptions, out: *mut *mut SddpmMesh) -> Status {
    ffi_boundary! {
        non_null(path, "path")?;
        non_null(out, "out")?;
        let bytes = CStr::from_ptr(path).to_bytes();
        #[cfg(unix)]
        let p = std::path::PathBuf::from(<std::ffi::OsStr as std::os::unix::ffi::OsStrExt>::from_bytes(bytes));
        #[cfg(not(unix))]
        let p = std::path::PathBuf::from(
            std::str::from_utf8(bytes).map_err(|_| Error::InvalidArgument("path is not UTF-8".into()))?,
        );
        let mesh = TriMesh::load(&p, &options(opts))?;
        *out = new_handle(mesh);
        Ok(())
    }
}

/// Create a mesh from flat arrays: `xyz` holds 3 x `nv` doubles, `tri` holds
/// 3 x `nt` vertex indices (0-based). The data are copied and welded as `opts`
/// says (NULL = defaults). Indices out of range: INVALID_ARGUMENT; NaN or
/// infinite coordinates, or nt = 0: INVALID_MESH.
///
/// # Safety
/// `xyz` must point to 3 nv doubles and `tri` to 3 nt indices (either may be
/// NULL only when its count is 0); `opts` NULL or valid; `out` valid.
#[no_mangle]
pub unsafe extern "C" fn sddpm_mesh_new_from_arrays(
    xyz: *const f64,
    nv: usize,
    tri: *const u32,
    nt: usize,
    opts: *const SddpmLoadOptions,
    out: *mut *mut SddpmMesh,
) -> Status {
    ffi_boundary! {
        non_null(out, "out")?;
        let nxyz = nv.checked_mul(3).ok_or_else(|| Error::InvalidArgument(format!("nv = {nv} is too large")))?;
        let ntri = nt.checked_mul(3).ok_or_else(|| Error::InvalidArgument(format!("nt = {nt} is too large")))?;
        let xyz: &[f64] = if nxyz == 0 { &[] } else { non_null(xyz, "xyz")?; std::slice::from_raw_parts(xyz, nxyz) };
        let tri: &[u32] = if ntri == 0 { &[] } else { non_null(tri, "tri")?; std::slice::from_raw_parts(tri, ntri) };
        let mesh = TriMesh::from_arrays(xyz, tri, &options(opts))?;
        *out = new_handle(mesh);
        Ok(())
    }
}

/// Release a mesh handle. NULL is a no-op.
///
/// # Safety
/// `mesh` must be NULL or a handle not yet freed.
#[no_mangle]
pub unsafe extern "C" fn sddpm_mesh_free(mesh: *mut SddpmMesh) {
    ffi_boundary! {
        if !mesh.is_null() {
            drop(Box::from_raw(mesh));
        }
    }
}

/// Number of vertices and triangles (after welding). Either out-pointer may be NULL.
///
/// # Safety
/// `mesh` a valid handle; out-pointers NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn sddpm_mesh_counts(mesh: *const SddpmMesh, vertices: *mut usize, triangles: *mut usize) -> Status {
    ffi_boundary! {
        let m = mesh_ref(mesh)?;
        if !vertices.is_null() {
            *vertices = m.mesh.vertices.len();
        }
        if !triangles.is_null() {
            *triangles = m.mesh.triangles.len();
        }
        Ok(())
    }
}

/// Measure and check the mesh (the report is computed once and cached). Succeeds
/// for any mesh: whether it can go on is `out->can_proceed`.
///
/// # Safety
/// `mesh` a valid handle; `out` valid.
#[no_mangle]
pub unsafe extern "C" fn sddpm_mesh_check(mesh: *const SddpmMesh, out: *mut SddpmMeshReport) -> Status {
    ffi_boundary! {
        let m = mesh_ref(mesh)?;
        non_null(out, "out")?;
        *out = m.report().into();
        Ok(())
    }
}

/// OK when the mesh can go on to meshing, else INVALID_MESH with a message
/// naming what is wrong and where (first edge / vertex with ids and coordinates, counts).
///
/// # Safety
/// `mesh` a valid handle.
#[no_mangle]
pub unsafe extern "C" fn sddpm_mesh_validate(mesh: *const SddpmMesh) -> Status {
    ffi_boundary! {
        let m = mesh_ref(mesh)?;
        match m.report().to_error() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

/// Genus of a closed manifold surface; INVALID_MESH when it is undefined.
///
/// # Safety
/// `mesh` a valid handle; `out` valid.
#[no_mangle]
pub unsafe extern "C" fn sddpm_mesh_genus(mesh: *const SddpmMesh, out: *mut i64) -> Status {
    ffi_boundary! {
        let m = mesh_ref(mesh)?;
        non_null(out, "out")?;
        let r = m.report();
        let g = r.genus.ok_or_else(|| {
            Error::InvalidMesh(format!(
                "genus is undefined: the surface is not a closed manifold ({} boundary edges, {} non-manifold edges, {} non-manifold vertices)",
                r.boundary_edges, r.non_manifold_edges, r.non_manifold_vertices
            ))
        })?;
        *out = g;
        Ok(())
    }
}

fn too_small(what: &str, capacity: usize, needed: usize, count: usize, per: &str) -> Error {
    Error::BufferTooSmall(format!("{what} buffer holds {capacity} values but {needed} are needed (3 x {count} {per})"))
}

/// Copy the vertex coordinates (x0 y0 z0 x1 ...) into `xyz`, which holds
/// `capacity` doubles; BUFFER_TOO_SMALL (nothing written) below 3 x vertices.
///
/// # Safety
/// `mesh` a valid handle; `xyz` points to `capacity` writable doubles.
#[no_mangle]
pub unsafe extern "C" fn sddpm_mesh_copy_vertices(mesh: *const SddpmMesh, xyz: *mut f64, capacity: usize) -> Status {
    ffi_boundary! {
        let m = mesh_ref(mesh)?;
        non_null(xyz, "xyz")?;
        let n = m.mesh.vertices.len();
        if capacity < 3 * n {
            return Err(too_small("vertex", capacity, 3 * n, n, "vertices"));
        }
        std::ptr::copy_nonoverlapping(m.mesh.vertices.as_ptr() as *const f64, xyz, 3 * n);
        Ok(())
    }
}

/// Copy the triangles (3 vertex indices each, counter-clockwise seen from
/// outside on a valid mesh) into `tri`, which holds `capacity` indices;
/// BUFFER_TOO_SMALL (nothing written) below 3 x triangles.
///
/// # Safety
/// `mesh` a valid handle; `tri` points to `capacity` writable indices.
#[no_mangle]
pub unsafe extern "C" fn sddpm_mesh_copy_triangles(mesh: *const SddpmMesh, tri: *mut u32, capacity: usize) -> Status {
    ffi_boundary! {
        let m = mesh_ref(mesh)?;
        non_null(tri, "tri")?;
        let n = m.mesh.triangles.len();
        if capacity < 3 * n {
            return Err(too_small("triangle", capacity, 3 * n, n, "triangles"));
        }
        std::ptr::copy_nonoverlapping(m.mesh.triangles.as_ptr() as *const u32, tri, 3 * n);
        Ok(())
    }
}

impl SddpmMesh {
    /// The mesh inside a handle (for other stages' exports).
    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }
}
