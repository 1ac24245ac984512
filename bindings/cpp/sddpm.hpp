// libsddpm C++17 API: a header-only RAII layer over the C API of sddpm.h.
//
// - Move-only owners (Options, Mesh, Contexts, Model, Polycube, HexMesh, Spline) free their handle
//   in the destructor; `get()` gives the C handle for calls this header does not wrap.
// - Options are set by name (`Options().set("hex.quality.pillow", false)`); every name, its
//   type, default and documentation: `Options::describe_json()`.
// - Every failing C call throws sddpm::Error, carrying the status and the message of
//   the library (the per-thread last error).
// - Arrays come back as std::vector; arrays go in as std::span-like (pointer, size)
//   views through `Span`.
// - Long calls take a std::function progress callback; returning false cancels
//   (the call then throws Error with status SDDPM_STATUS_CANCELLED). An exception
//   thrown by the callback is caught at the C boundary, the call is cancelled, and
//   the exception is rethrown to the caller after the C call returns.
//
// Nothing here allocates behind the library's back: the library copies into the
// vectors this header sizes from the library's counts.
#ifndef SDDPM_HPP
#define SDDPM_HPP

#include "sddpm.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace sddpm {

/// A failed call: the status number and the library's message.
class Error : public std::runtime_error {
 public:
  Error(sddpm_status status, const std::string& message)
      : std::runtime_error(std::string(sddpm_status_name(status)) + ": " + message), status_(status), message_(message) {}
  sddpm_status status() const noexcept { return status_; }
  const std::string& message() const noexcept { return message_; }
  const char* name() const noexcept { return sddpm_status_name(status_); }

 private:
  sddpm_status status_;
  std::string message_;
};

namespace detail {
inline std::string last_message() {
  size_t need = 0;
  sddpm_last_error_message(nullptr, 0, &need);
  if (need == 0) return {};
  std::string s(need, '\0');
  if (sddpm_last_error_message(&s[0], s.size(), &need) != SDDPM_STATUS_OK) return {};
  s.resize(need > 0 ? need - 1 : 0);
  return s;
}

inline void check(sddpm_status s) {
  if (s != SDDPM_STATUS_OK) throw Error(s, last_message());
}

/// Adapts a std::function to the C callback; keeps an exception for rethrow.
struct Progress {
  std::function<bool(double, const std::string&)> fn;
  std::exception_ptr error;
  static int call(double fraction, const char* stage, void* self) {
    auto* p = static_cast<Progress*>(self);
    if (!p->fn) return 0;
    try {
      return p->fn(fraction, stage ? std::string(stage) : std::string()) ? 0 : 1;
    } catch (...) {
      p->error = std::current_exception();
      return 1;
    }
  }
  sddpm_progress_cb cb() const { return fn ? &Progress::call : nullptr; }
  void* data() { return this; }
  /// After the C call: rethrow the callback's exception, else check the status.
  void finish(sddpm_status s) {
    if (error) std::rethrow_exception(error);
    check(s);
  }
};

template <typename T, void (*Free)(T*)>
class Owner {
 public:
  Owner() = default;
  explicit Owner(T* p) noexcept : p_(p) {}
  Owner(const Owner&) = delete;
  Owner& operator=(const Owner&) = delete;
  Owner(Owner&& o) noexcept : p_(std::exchange(o.p_, nullptr)) {}
  Owner& operator=(Owner&& o) noexcept {
    if (this != &o) {
      reset();
      p_ = std::exchange(o.p_, nullptr);
    }
    return *this;
  }
  ~Owner() { reset(); }
  void reset() noexcept {
    if (p_) Free(p_);
    p_ = nullptr;
  }
  T* get() const noexcept { return p_; }
  explicit operator bool() const noexcept { return p_ != nullptr; }

 private:
  T* p_ = nullptr;
};
}  // namespace detail

/// A read-only view of caller data (std::span without requiring C++20).
template <typename T>
struct Span {
  const T* data = nullptr;
  size_t size = 0;
  Span() = default;
  Span(const T* d, size_t n) : data(d), size(n) {}
  Span(const std::vector<T>& v) : data(v.data()), size(v.size()) {}  // NOLINT: implicit by design
};

using ProgressFn = std::function<bool(double fraction, const std::string& stage)>;

inline uint32_t abi_version() { return sddpm_abi_version(); }
inline std::string version() { return sddpm_version_string(); }

// ------------------------------------------------------------------ options

/// The pipeline's options by name ("hex.quality.pillow", "polycube.verify.tau_cd",
/// "hex_candidates"), each checked when set: an unknown name, a value of another
/// type or out of range throws Error (INVALID_ARGUMENT, naming the option) and
/// leaves the options as they were.
class Options {
 public:
  Options() {
    sddpm_options* o = nullptr;
    detail::check(sddpm_options_new(&o));
    h_ = detail::Owner<sddpm_options, sddpm_options_free>(o);
  }
  /// A number or integer option (an integer option takes a whole number).
  Options& set(const std::string& name, double value) {
    detail::check(sddpm_options_set_number(h_.get(), name.c_str(), value));
    return *this;
  }
  template <typename T, typename std::enable_if<std::is_integral<T>::value && !std::is_same<T, bool>::value, int>::type = 0>
  Options& set(const std::string& name, T value) {
    return set(name, static_cast<double>(value));
  }
  Options& set(const std::string& name, bool value) {
    detail::check(sddpm_options_set_bool(h_.get(), name.c_str(), value));
    return *this;
  }
  Options& set(const std::string& name, const std::string& value) {
    detail::check(sddpm_options_set_string(h_.get(), name.c_str(), value.c_str()));
    return *this;
  }
  Options& set(const std::string& name, const char* value) { return set(name, std::string(value)); }
  /// Unset an option that may be unset (e.g. "hex.map.level": chosen automatically).
  Options& unset(const std::string& name) {
    detail::check(sddpm_options_unset(h_.get(), name.c_str()));
    return *this;
  }
  double get_number(const std::string& name) const {
    double x = 0;
    detail::check(sddpm_options_get_number(h_.get(), name.c_str(), &x));
    return x;
  }
  bool get_bool(const std::string& name) const {
    bool b = false;
    detail::check(sddpm_options_get_bool(h_.get(), name.c_str(), &b));
    return b;
  }
  std::string get_string(const std::string& name) const {
    size_t need = 0;
    sddpm_status st = sddpm_options_get_string(h_.get(), name.c_str(), nullptr, 0, &need);
    if (st != SDDPM_STATUS_BUFFER_TOO_SMALL) detail::check(st);
    std::string s(need, '\0');
    detail::check(sddpm_options_get_string(h_.get(), name.c_str(), &s[0], s.size(), &need));
    s.resize(need > 0 ? need - 1 : 0);
    return s;
  }
  /// Every option as a JSON object: name -> {value, default, type, nullable, doc}.
  std::string describe_json() const {
    size_t need = 0;
    sddpm_options_describe_json(h_.get(), nullptr, 0, &need);
    std::string s(need, '\0');
    detail::check(sddpm_options_describe_json(h_.get(), &s[0], s.size(), &need));
    s.resize(need > 0 ? need - 1 : 0);
    return s;
  }
  const sddpm_options* get() const noexcept { return h_.get(); }

 private:
  detail::Owner<sddpm_options, sddpm_options_free> h_;
};

namespace detail {
inline const sddpm_options* opts(const Options* o) { return o ? o->get() : nullptr; }
}  // namespace detail

// ------------------------------------------------------------------ mesh

class Mesh {
 public:
  /// Load an OBJ / STL / OFF file (default options: weld 1e-9 of the diagonal).
  static Mesh load(const std::string& path) { return load(path, default_options()); }
  static Mesh load(const std::string& path, const sddpm_load_options& opts) {
    sddpm_mesh* m = nullptr;
    detail::check(sddpm_mesh_load(path.c_str(), &opts, &m));
    return Mesh(m);
  }
  /// From flat arrays: 3 coordinates per vertex, 3 indices per triangle.
  static Mesh from_arrays(Span<double> xyz, Span<uint32_t> tri) {
    if (xyz.size % 3 != 0 || tri.size % 3 != 0) throw Error(SDDPM_STATUS_INVALID_ARGUMENT, "array lengths must be multiples of 3");
    sddpm_mesh* m = nullptr;
    detail::check(sddpm_mesh_new_from_arrays(xyz.data, xyz.size / 3, tri.data, tri.size / 3, nullptr, &m));
    return Mesh(m);
  }
  static sddpm_load_options default_options() {
    sddpm_load_options o{};
    detail::check(sddpm_load_options_default(&o));
    return o;
  }

  size_t vertex_count() const { return counts().first; }
  size_t triangle_count() const { return counts().second; }
  sddpm_mesh_report check() const {
    sddpm_mesh_report r{};
    detail::check(sddpm_mesh_check(h_.get(), &r));
    return r;
  }
  /// Throws (INVALID_MESH, naming the problem) when the mesh cannot go on to meshing.
  void validate() const { detail::check(sddpm_mesh_validate(h_.get())); }
  int64_t genus() const {
    int64_t g = 0;
    detail::check(sddpm_mesh_genus(h_.get(), &g));
    return g;
  }
  std::vector<double> vertices() const {
    std::vector<double> v(3 * vertex_count());
    detail::check(sddpm_mesh_copy_vertices(h_.get(), v.data(), v.size()));
    return v;
  }
  std::vector<uint32_t> triangles() const {
    std::vector<uint32_t> t(3 * triangle_count());
    detail::check(sddpm_mesh_copy_triangles(h_.get(), t.data(), t.size()));
    return t;
  }
  const sddpm_mesh* get() const noexcept { return h_.get(); }

 private:
  explicit Mesh(sddpm_mesh* m) : h_(m) {}
  std::pair<size_t, size_t> counts() const {
    size_t v = 0, t = 0;
    detail::check(sddpm_mesh_counts(h_.get(), &v, &t));
    return {v, t};
  }
  detail::Owner<sddpm_mesh, sddpm_mesh_free> h_;
};

// ------------------------------------------------------------------ contexts

using Labels = std::array<int32_t, 12>;

/// A stack of one or more contexts (12 labels each, cell-index order).
class Contexts {
 public:
  /// "cube,THC+Z,0,..." (several separated by ';').
  static Contexts parse(const std::string& text) {
    sddpm_context* c = nullptr;
    detail::check(sddpm_context_new_from_string(text.c_str(), &c));
    return Contexts(c);
  }
  static Contexts from_labels(const std::vector<Labels>& labels) {
    std::vector<int32_t> flat;
    for (const auto& l : labels) flat.insert(flat.end(), l.begin(), l.end());
    sddpm_context* c = nullptr;
    detail::check(sddpm_context_new_from_labels(flat.data(), flat.size(), &c));
    return Contexts(c);
  }
  static Contexts from_one_hot(Span<float> v) {
    sddpm_context* c = nullptr;
    detail::check(sddpm_context_new_from_one_hot(v.data, v.size, &c));
    return Contexts(c);
  }
  /// Every valid context satisfying the constraints.
  static Contexts from_constraints(const sddpm_constraints& k) {
    sddpm_context* c = nullptr;
    detail::check(sddpm_context_new_from_constraints(&k, &c));
    return Contexts(c);
  }
  static sddpm_constraints default_constraints() {
    sddpm_constraints k{};
    detail::check(sddpm_constraints_default(&k));
    return k;
  }

  size_t size() const {
    size_t n = 0;
    detail::check(sddpm_context_count(h_.get(), &n));
    return n;
  }
  Labels labels(size_t i) const {
    Labels l{};
    detail::check(sddpm_context_get_labels(h_.get(), i, l.data(), l.size()));
    return l;
  }
  std::vector<float> one_hot(size_t i) const {
    std::vector<float> v(132);
    detail::check(sddpm_context_get_one_hot(h_.get(), i, v.data(), v.size()));
    return v;
  }
  /// Genus of the assembled solid (throws INVALID_CONTEXT with the reason if invalid).
  int64_t genus(size_t i) const {
    int64_t g = 0;
    detail::check(sddpm_context_genus(h_.get(), i, &g));
    return g;
  }
  /// Empty string when valid, else the reason.
  std::string invalid_reason(size_t i) const {
    char buf[512] = {0};
    bool valid = false;
    detail::check(sddpm_context_validity(h_.get(), i, buf, sizeof buf, &valid));
    return valid ? std::string() : std::string(buf);
  }
  void write_obj(size_t i, const std::string& path) const { detail::check(sddpm_context_write_obj(h_.get(), i, path.c_str())); }
  const sddpm_context* get() const noexcept { return h_.get(); }

 private:
  explicit Contexts(sddpm_context* c) : h_(c) {}
  detail::Owner<sddpm_context, sddpm_context_free> h_;
};

// ------------------------------------------------------------------ model

/// The diffusion model (immutable: one Model may serve several threads at once).
class Model {
 public:
  /// The model embedded in the library.
  static Model embedded() {
    sddpm_model* m = nullptr;
    detail::check(sddpm_model_new_default(&m));
    return Model(m);
  }
  static Model from_file(const std::string& path) {
    sddpm_model* m = nullptr;
    detail::check(sddpm_model_new_from_file(path.c_str(), &m));
    return Model(m);
  }
  static Model from_bytes(Span<uint8_t> bytes) {
    sddpm_model* m = nullptr;
    detail::check(sddpm_model_new_from_bytes(bytes.data, bytes.size, &m));
    return Model(m);
  }
  sddpm_model_info info() const {
    sddpm_model_info i{};
    detail::check(sddpm_model_get_info(h_.get(), &i));
    return i;
  }
  const sddpm_model* get() const noexcept { return h_.get(); }

 private:
  explicit Model(sddpm_model* m) : h_(m) {}
  detail::Owner<sddpm_model, sddpm_model_free> h_;
};

// ------------------------------------------------------------------ polycube

/// What to generate from: complete contexts, constraints, splitting ratios, or
/// (all empty) the automated search.
struct PolycubeRequest {
  const Contexts* contexts = nullptr;
  const sddpm_constraints* constraints = nullptr;
  const std::array<double, 7>* ratios = nullptr;
};

/// The result of a polycube search (all candidates with their verification).
class Polycube {
 public:
  /// `opts` null: the defaults (the "polycube.*" and "auto.*" options are used).
  static Polycube generate(const Model& model, const Mesh& mesh, const PolycubeRequest& req = {}, const Options* opts = nullptr,
                           ProgressFn progress = {}) {
    detail::Progress p{std::move(progress), nullptr};
    sddpm_polycube* out = nullptr;
    sddpm_status s = sddpm_generate_polycube(model.get(), mesh.get(), req.contexts ? req.contexts->get() : nullptr, req.constraints,
                                             req.ratios ? req.ratios->data() : nullptr, detail::opts(opts), p.cb(), p.data(), &out);
    Polycube pc(out);  // owns the handle even if finish() throws
    p.finish(s);
    return pc;
  }

  /// True when a candidate was accepted.
  bool accepted() const { return sddpm_polycube_status(h_.get()) == SDDPM_STATUS_OK; }
  /// Throws VERIFICATION_FAILED (with the reason) when no candidate was accepted.
  void require_accepted() const { detail::check(sddpm_polycube_status(h_.get())); }
  /// The chosen candidate's labels (throws when none was accepted).
  Labels labels() const {
    Labels l{};
    detail::check(sddpm_polycube_labels(h_.get(), l.data(), l.size()));
    return l;
  }
  std::vector<sddpm_candidate_report> candidates() const {
    size_t n = 0;
    detail::check(sddpm_polycube_candidate_count(h_.get(), &n));
    std::vector<sddpm_candidate_report> v(n);
    for (size_t i = 0; i < n; ++i) detail::check(sddpm_polycube_candidate(h_.get(), i, &v[i]));
    return v;
  }
  std::string report_json() const {
    size_t need = 0;
    sddpm_polycube_report_json(h_.get(), nullptr, 0, &need);
    std::string s(need, '\0');
    detail::check(sddpm_polycube_report_json(h_.get(), &s[0], s.size(), &need));
    s.resize(need > 0 ? need - 1 : 0);
    return s;
  }
  /// Output points and the input samples they came from (3 doubles each, 6144 points).
  std::pair<std::vector<double>, std::vector<double>> points() const {
    const size_t n = 3 * 6144;
    std::vector<double> out(n), in(n);
    detail::check(sddpm_polycube_copy_points(h_.get(), out.data(), in.data(), n));
    return {std::move(out), std::move(in)};
  }
  const sddpm_polycube* get() const noexcept { return h_.get(); }

 private:
  explicit Polycube(sddpm_polycube* p) : h_(p) {}
  detail::Owner<sddpm_polycube, sddpm_polycube_free> h_;
};

// ------------------------------------------------------------------ hex mesh

/// An all-hex mesh (VTK_HEXAHEDRON node order) with its quality.
class HexMesh {
 public:
  /// Build from a polycube result as the main job does (its best candidates, the
  /// grid-based fallback when none meets the goals); `opts` null: the defaults
  /// (the "hex.*" options, "hex_candidates", "accept_unverified", "require_valid_hex").
  static HexMesh build(const Polycube& pc, const Options* opts = nullptr, ProgressFn progress = {}) {
    detail::Progress p{std::move(progress), nullptr};
    sddpm_hex_mesh* out = nullptr;
    sddpm_status s = sddpm_hex_mesh_build(pc.get(), detail::opts(opts), p.cb(), p.data(), &out);
    HexMesh h(out);
    p.finish(s);
    return h;
  }
  /// From the caller's arrays: 3 doubles per node, 8 indices per element.
  static HexMesh from_arrays(Span<double> xyz, Span<uint32_t> conn) {
    if (xyz.size % 3 != 0 || conn.size % 8 != 0) throw Error(SDDPM_STATUS_INVALID_ARGUMENT, "xyz needs 3 values per node and conn 8 per element");
    sddpm_hex_mesh* out = nullptr;
    detail::check(sddpm_hex_mesh_new_from_arrays(xyz.data, xyz.size / 3, conn.data, conn.size / 8, &out));
    return HexMesh(out);
  }
  size_t node_count() const { return counts().first; }
  size_t element_count() const { return counts().second; }
  std::vector<double> nodes() const {
    std::vector<double> v(3 * node_count());
    detail::check(sddpm_hex_mesh_copy_nodes(h_.get(), v.data(), v.size()));
    return v;
  }
  std::vector<uint32_t> elements() const {
    std::vector<uint32_t> v(8 * element_count());
    detail::check(sddpm_hex_mesh_copy_elements(h_.get(), v.data(), v.size()));
    return v;
  }
  std::vector<double> scaled_jacobian() const {
    std::vector<double> v(element_count());
    detail::check(sddpm_hex_mesh_copy_scaled_jacobian(h_.get(), v.data(), v.size()));
    return v;
  }
  std::vector<size_t> histogram(size_t bins = 20) const {
    std::vector<size_t> v(bins);
    detail::check(sddpm_hex_mesh_histogram(h_.get(), v.data(), bins));
    return v;
  }
  sddpm_hex_quality quality() const {
    sddpm_hex_quality q{};
    detail::check(sddpm_hex_mesh_quality(h_.get(), &q));
    return q;
  }
  std::string report_json() const {
    size_t need = 0;
    sddpm_hex_mesh_report_json(h_.get(), nullptr, 0, &need);
    std::string s(need, '\0');
    detail::check(sddpm_hex_mesh_report_json(h_.get(), &s[0], s.size(), &need));
    s.resize(need > 0 ? need - 1 : 0);
    return s;
  }
  void write(const std::string& path, sddpm_hex_format format) const { detail::check(sddpm_hex_mesh_write(h_.get(), path.c_str(), format)); }
  const sddpm_hex_mesh* get() const noexcept { return h_.get(); }

 private:
  explicit HexMesh(sddpm_hex_mesh* h) : h_(h) {}
  std::pair<size_t, size_t> counts() const {
    size_t n = 0, e = 0;
    detail::check(sddpm_hex_mesh_counts(h_.get(), &n, &e));
    return {n, e};
  }
  detail::Owner<sddpm_hex_mesh, sddpm_hex_mesh_free> h_;
};

// ------------------------------------------------------------------ spline

/// One element's Bézier extraction: basis ids and rows of 64 Bernstein coefficients.
struct Extraction {
  std::vector<uint32_t> basis;
  std::vector<double> op;  // basis.size() x 64, row-major
};

/// The TH-spline3D volume with its Bézier extraction.
class Spline {
 public:
  /// Fitted to `surface`, or to the surface the hex mesh was built for when null;
  /// `opts` null: the defaults (the "spline.*" options are used).
  static Spline build(const HexMesh& hex, const Mesh* surface = nullptr, const Options* opts = nullptr, ProgressFn progress = {}) {
    detail::Progress p{std::move(progress), nullptr};
    sddpm_spline* out = nullptr;
    sddpm_status s = sddpm_spline_build(hex.get(), surface ? surface->get() : nullptr, detail::opts(opts), p.cb(), p.data(), &out);
    Spline sp(out);
    p.finish(s);
    return sp;
  }
  size_t element_count() const { return counts().first; }
  size_t basis_count() const { return counts().second; }
  Extraction extraction(size_t element) const {
    size_t n = 0;
    sddpm_spline_element_extraction(h_.get(), element, nullptr, nullptr, 0, &n);
    Extraction x{std::vector<uint32_t>(n), std::vector<double>(64 * n)};
    detail::check(sddpm_spline_element_extraction(h_.get(), element, x.basis.data(), x.op.data(), n, &n));
    return x;
  }
  /// The map at (u, v, w) in [0, 1]^3 of `element`, and its Jacobian (row-major).
  std::pair<std::array<double, 3>, std::array<double, 9>> evaluate(size_t element, double u, double v, double w) const {
    std::array<double, 3> x{};
    std::array<double, 9> j{};
    detail::check(sddpm_spline_evaluate(h_.get(), element, u, v, w, x.data(), j.data()));
    return {x, j};
  }
  /// spline.bext, model.k, spline.vtk, spline_control.vtk into `dir`.
  void write(const std::string& dir) const { detail::check(sddpm_spline_write(h_.get(), dir.c_str())); }
  std::string report_json() const {
    size_t need = 0;
    sddpm_spline_report_json(h_.get(), nullptr, 0, &need);
    std::string s(need, '\0');
    detail::check(sddpm_spline_report_json(h_.get(), &s[0], s.size(), &need));
    s.resize(need > 0 ? need - 1 : 0);
    return s;
  }
  const sddpm_spline* get() const noexcept { return h_.get(); }

 private:
  explicit Spline(sddpm_spline* s) : h_(s) {}
  std::pair<size_t, size_t> counts() const {
    size_t e = 0, b = 0;
    detail::check(sddpm_spline_counts(h_.get(), &e, &b));
    return {e, b};
  }
  detail::Owner<sddpm_spline, sddpm_spline_free> h_;
};

}  // namespace sddpm

#endif  // SDDPM_HPP
