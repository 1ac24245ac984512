// The C++ RAII layer (bindings/cpp/sddpm.hpp), used alone: no call to the C API here.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <type_traits>
#include <vector>

#include "sddpm.hpp"

namespace {
std::string mesh(const std::string& name) { return std::string(SDDPM_TEST_DATA) + "/" + name; }

sddpm::Options fast() {
  sddpm::Options o;
  o.set("polycube.sampler.steps", 10);
  return o;
}
}  // namespace

static_assert(!std::is_copy_constructible_v<sddpm::Mesh>, "owners are move-only");
static_assert(std::is_nothrow_move_constructible_v<sddpm::Model>, "owners move without throwing");

TEST(CppApi, MeshContextsAndErrors) {
  EXPECT_EQ(sddpm::abi_version(), static_cast<uint32_t>(SDDPM_ABI_VERSION));
  auto m = sddpm::Mesh::load(mesh("cgal_hole.off"));
  EXPECT_EQ(m.genus(), 1);
  EXPECT_NO_THROW(m.validate());
  auto r = m.check();
  EXPECT_TRUE(r.closed);
  EXPECT_EQ(m.vertices().size(), 3 * m.vertex_count());
  // arrays round trip
  auto again = sddpm::Mesh::from_arrays(m.vertices(), m.triangles());
  EXPECT_EQ(again.triangle_count(), m.triangle_count());
  EXPECT_EQ(again.genus(), 1);
  // moved-from owners are empty and harmless
  auto moved = std::move(again);
  EXPECT_EQ(moved.genus(), 1);

  try {
    sddpm::Mesh::load("/nonexistent/part.stl");
    FAIL() << "no exception";
  } catch (const sddpm::Error& e) {
    EXPECT_EQ(e.status(), SDDPM_STATUS_IO);
    EXPECT_NE(e.message().find("/nonexistent/part.stl"), std::string::npos) << e.message();
  }
  auto open = sddpm::Mesh::load(mesh("bad/cgal_mech-holes-shark.off"));
  try {
    open.validate();
    FAIL() << "an open mesh validated";
  } catch (const sddpm::Error& e) {
    EXPECT_EQ(e.status(), SDDPM_STATUS_INVALID_MESH);
  }

  auto c = sddpm::Contexts::parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0;cube,cube,0,0,0,0,0,0,0,0,0,0");
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.genus(0), 1);
  EXPECT_EQ(c.genus(1), 0);
  EXPECT_EQ(c.labels(1)[1], 1);
  EXPECT_EQ(c.invalid_reason(0), "");
  auto from_hot = sddpm::Contexts::from_one_hot(c.one_hot(0));
  EXPECT_EQ(from_hot.labels(0), c.labels(0));
  auto diagonal = sddpm::Contexts::parse("cube,0,0,0,cube,0,0,0,0,0,0,0");
  EXPECT_NE(diagonal.invalid_reason(0), "");
  EXPECT_THROW(sddpm::Contexts::parse("cube,0,0"), sddpm::Error);
  auto k = sddpm::Contexts::default_constraints();
  k.cube = 3;
  k.thc = 0;
  k.bhc = 0;
  k.allowed_mask = 0x3f;  // the lower layer
  auto all = sddpm::Contexts::from_constraints(k);
  EXPECT_GT(all.size(), 0u);
  for (size_t i = 0; i < all.size(); ++i) EXPECT_EQ(all.genus(i), 0);
}

// Options by name: set and read back each type, refusals naming the option, the description.
TEST(CppApi, Options) {
  sddpm::Options o;
  EXPECT_TRUE(o.get_bool("hex.quality.pillow"));
  o.set("hex.quality.pillow", false).set("hex.goals.hausdorff", 0.02).set("hex_candidates", 2).set("polycube.orientations", "SignFlips");
  o.set("polycube.seed", static_cast<uint64_t>(7));
  EXPECT_FALSE(o.get_bool("hex.quality.pillow"));
  EXPECT_DOUBLE_EQ(o.get_number("hex.goals.hausdorff"), 0.02);
  EXPECT_EQ(o.get_number("hex_candidates"), 2.0);
  EXPECT_EQ(o.get_number("polycube.seed"), 7.0);
  EXPECT_EQ(o.get_string("polycube.orientations"), "SignFlips");
  o.set("hex.map.level", 3);
  EXPECT_EQ(o.get_number("hex.map.level"), 3.0);
  o.unset("hex.map.level");
  EXPECT_THROW(o.get_number("hex.map.level"), sddpm::Error);
  try {
    o.set("hex.quality.pilow", true);
    FAIL() << "unknown option accepted";
  } catch (const sddpm::Error& e) {
    EXPECT_EQ(e.status(), SDDPM_STATUS_INVALID_ARGUMENT);
    EXPECT_NE(e.message().find("unknown option \"hex.quality.pilow\""), std::string::npos) << e.message();
  }
  try {
    o.set("hex.fallback.resolution", 1);
    FAIL() << "resolution 1 accepted";
  } catch (const sddpm::Error& e) {
    EXPECT_EQ(e.status(), SDDPM_STATUS_INVALID_ARGUMENT);
    EXPECT_NE(e.message().find("option hex.fallback.resolution must be between 2 and 192, got 1"), std::string::npos) << e.message();
  }
  EXPECT_THROW(o.set("hex.quality.pillow", 1.0), sddpm::Error);  // a bool option
  EXPECT_FALSE(o.get_bool("hex.quality.pillow"));                // unchanged by the refusals
  auto d = o.describe_json();
  for (auto name : {"polycube.sampler.steps", "polycube.verify.tau_cd", "auto.resolution", "hex.map.level", "hex.quality.pillow",
                    "hex.fallback.enabled", "hex.goals.hausdorff", "spline.fit.enabled", "hex_candidates", "accept_unverified"}) {
    EXPECT_NE(d.find(std::string("\"") + name + "\":{"), std::string::npos) << name;
  }
  static_assert(!std::is_copy_constructible_v<sddpm::Options>, "options are move-only");
}

TEST(CppApi, PolycubeProgressAndCancel) {
  auto model = sddpm::Model::embedded();
  EXPECT_GT(model.info().parameters, 0u);
  auto m = sddpm::Mesh::load(mesh("cgal_hole.off"));
  auto ctx = sddpm::Contexts::parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0");
  const auto opts = fast();
  int calls = 0;
  auto pc = sddpm::Polycube::generate(model, m, {&ctx, nullptr, nullptr}, &opts, [&](double f, const std::string&) {
    EXPECT_GE(f, 0.0);
    EXPECT_LE(f, 1.0);
    ++calls;
    return true;
  });
  EXPECT_GT(calls, 0);
  auto cands = pc.candidates();
  ASSERT_EQ(cands.size(), 1u);
  EXPECT_EQ(cands[0].labels[0], 2);
  EXPECT_NE(pc.report_json().find("\"candidates\""), std::string::npos);
  if (pc.accepted()) {
    EXPECT_EQ(pc.labels()[0], 2);
    auto pts = pc.points();
    EXPECT_EQ(pts.first.size(), 3u * 6144u);
  } else {
    EXPECT_THROW(pc.require_accepted(), sddpm::Error);
  }

  // genus mismatch is refused before diffusion
  auto cube = sddpm::Contexts::parse("cube,0,0,0,0,0,0,0,0,0,0,0");
  try {
    sddpm::Polycube::generate(model, m, {&cube, nullptr, nullptr}, &opts);
    FAIL() << "genus mismatch accepted";
  } catch (const sddpm::Error& e) {
    EXPECT_EQ(e.status(), SDDPM_STATUS_GENUS_MISMATCH);
    EXPECT_NE(e.message().find("genus 1"), std::string::npos) << e.message();
  }
  // cancel from the callback
  try {
    sddpm::Polycube::generate(model, m, {&ctx, nullptr, nullptr}, &opts, [](double, const std::string&) { return false; });
    FAIL() << "not cancelled";
  } catch (const sddpm::Error& e) {
    EXPECT_EQ(e.status(), SDDPM_STATUS_CANCELLED);
  }
  // an exception in the callback cancels the call and reaches the caller
  struct Stop {};
  EXPECT_THROW(sddpm::Polycube::generate(model, m, {&ctx, nullptr, nullptr}, &opts, [](double, const std::string&) -> bool { throw Stop{}; }), Stop);
}

// The whole pipeline through the C++ layer: mesh -> polycube -> hex mesh -> spline -> files.
TEST(CppApi, WholePipeline) {
  auto model = sddpm::Model::embedded();
  auto m = sddpm::Mesh::load(mesh("cgal_hole.off"));
  auto ctx = sddpm::Contexts::parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0");
  auto opts = fast();
  auto pc = sddpm::Polycube::generate(model, m, {&ctx, nullptr, nullptr}, &opts);
  opts.set("hex.map.level", 1);
  auto hex = sddpm::HexMesh::build(pc, &opts);
  auto q = hex.quality();
  EXPECT_EQ(q.elements, hex.element_count());
  EXPECT_EQ(q.inverted, 0u);
  EXPECT_GT(q.min_scaled_jacobian, 0.2);
  EXPECT_LT(q.hausdorff_relative, 0.01);
  EXPECT_EQ(q.level, 1);
  auto sj = hex.scaled_jacobian();
  ASSERT_EQ(sj.size(), hex.element_count());
  EXPECT_DOUBLE_EQ(*std::min_element(sj.begin(), sj.end()), q.min_scaled_jacobian);
  size_t total = 0;
  for (auto c : hex.histogram()) total += c;
  EXPECT_EQ(total, hex.element_count());
  auto conn = hex.elements();
  for (auto i : conn) ASSERT_LT(i, hex.node_count());
  EXPECT_NE(hex.report_json().find("\"min_scaled_jacobian\""), std::string::npos);

  auto sp = sddpm::Spline::build(hex);
  EXPECT_EQ(sp.element_count(), hex.element_count());
  EXPECT_GT(sp.basis_count(), 0u);
  // partition of unity: every Bernstein column of an element's operator sums to 1
  auto x = sp.extraction(0);
  ASSERT_FALSE(x.basis.empty());
  for (int b = 0; b < 64; ++b) {
    double s = 0;
    for (size_t r = 0; r < x.basis.size(); ++r) s += x.op[r * 64 + b];
    EXPECT_NEAR(s, 1.0, 1e-12) << "column " << b;
  }
  auto [p, j] = sp.evaluate(0, 0.5, 0.5, 0.5);
  double det = j[0] * (j[4] * j[8] - j[5] * j[7]) - j[1] * (j[3] * j[8] - j[5] * j[6]) + j[2] * (j[3] * j[7] - j[4] * j[6]);
  EXPECT_GT(det, 0.0);
  EXPECT_THROW(sp.evaluate(0, 1.5, 0.5, 0.5), sddpm::Error);
  EXPECT_THROW(sp.extraction(sp.element_count()), sddpm::Error);
  auto dir = std::filesystem::temp_directory_path() / ("sddpm-cpp-api-" + std::to_string(::getpid()));
  sp.write(dir.string());
  hex.write((dir / "hex.vtu").string(), SDDPM_HEX_FORMAT_VTU);
  for (auto f : {"spline.bext", "model.k", "hex.vtu"}) EXPECT_TRUE(std::filesystem::exists(dir / f)) << f;
  std::filesystem::remove_all(dir);

  // a hex mesh from arrays: the unit cube
  std::vector<double> xyz = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1};
  std::vector<uint32_t> cube = {0, 1, 2, 3, 4, 5, 6, 7};
  auto one = sddpm::HexMesh::from_arrays(xyz, cube);
  EXPECT_DOUBLE_EQ(one.quality().min_scaled_jacobian, 1.0);
  std::vector<uint32_t> bad = {0, 1, 2, 3, 4, 5, 6, 9};
  try {
    sddpm::HexMesh::from_arrays(xyz, bad);
    FAIL() << "out-of-range node accepted";
  } catch (const sddpm::Error& e) {
    EXPECT_EQ(e.status(), SDDPM_STATUS_INVALID_ARGUMENT);
    EXPECT_NE(e.message().find("element 0"), std::string::npos) << e.message();
  }
}
