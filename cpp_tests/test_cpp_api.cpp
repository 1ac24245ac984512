// The C++ RAII layer (bindings/cpp/sddpm.hpp), used alone: no call to the C API here.
#include <gtest/gtest.h>

#include <string>
#include <type_traits>
#include <vector>

#include "sddpm.hpp"

namespace {
std::string mesh(const std::string& name) { return std::string(SDDPM_TEST_DATA) + "/" + name; }

sddpm_polycube_options fast() {
  auto o = sddpm::default_polycube_options();
  o.sampler_steps = 10;
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

TEST(CppApi, PolycubeProgressAndCancel) {
  auto model = sddpm::Model::embedded();
  EXPECT_GT(model.info().parameters, 0u);
  auto m = sddpm::Mesh::load(mesh("cgal_hole.off"));
  auto ctx = sddpm::Contexts::parse("THC+Z,0,0,0,0,0,0,0,0,0,0,0");
  int calls = 0;
  auto pc = sddpm::Polycube::generate(model, m, {&ctx, nullptr, nullptr}, fast(), [&](double f, const std::string&) {
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
    sddpm::Polycube::generate(model, m, {&cube, nullptr, nullptr}, fast());
    FAIL() << "genus mismatch accepted";
  } catch (const sddpm::Error& e) {
    EXPECT_EQ(e.status(), SDDPM_STATUS_GENUS_MISMATCH);
    EXPECT_NE(e.message().find("genus 1"), std::string::npos) << e.message();
  }
  // cancel from the callback
  try {
    sddpm::Polycube::generate(model, m, {&ctx, nullptr, nullptr}, fast(), [](double, const std::string&) { return false; });
    FAIL() << "not cancelled";
  } catch (const sddpm::Error& e) {
    EXPECT_EQ(e.status(), SDDPM_STATUS_CANCELLED);
  }
  // an exception in the callback cancels the call and reaches the caller
  struct Stop {};
  EXPECT_THROW(sddpm::Polycube::generate(model, m, {&ctx, nullptr, nullptr}, fast(), [](double, const std::string&) -> bool { throw Stop{}; }), Stop);
}
