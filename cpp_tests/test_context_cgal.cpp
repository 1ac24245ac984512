// The assembled genus, closedness and volume of contexts against CGAL 5.5 on the
// exported polycube surfaces: all 10 single primitives, all 10 full grids and 500
// valid random contexts. The volume of an assembly is its number of sub-voxels
// times (1/3)^3 (cell units): 27 per cube, 24 per THC, 25 per BHC.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/IO/OBJ.h>
#include <CGAL/boost/graph/helpers.h>

#include <array>
#include <random>

#include "common.hpp"

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<K::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;
using namespace sddpm_test;
using Labels = std::array<int32_t, 12>;

namespace {

int subvoxels(int label) { return label == 0 ? 0 : label == 1 ? 27 : label <= 4 ? 24 : 25; }

struct Measured {
  bool valid = false;
  int64_t genus = -1;
};

Measured ours(const Labels& l) {
  sddpm_context* c = nullptr;
  EXPECT_EQ(sddpm_context_new_from_labels(l.data(), 12, &c), SDDPM_STATUS_OK) << last_error();
  Measured m;
  char reason[512];
  EXPECT_EQ(sddpm_context_validity(c, 0, reason, sizeof reason, &m.valid), SDDPM_STATUS_OK);
  sddpm_status s = sddpm_context_genus(c, 0, &m.genus);
  EXPECT_EQ(s == SDDPM_STATUS_OK, m.valid) << reason;
  if (!m.valid) EXPECT_EQ(s, SDDPM_STATUS_INVALID_CONTEXT);
  sddpm_context_free(c);
  return m;
}

// Export the assembled surface and compare it with CGAL; returns false if CGAL could not read it.
void compare(const Labels& l, const std::string& tag) {
  Measured m = ours(l);
  if (!m.valid) return;
  sddpm_context* c = nullptr;
  ASSERT_EQ(sddpm_context_new_from_labels(l.data(), 12, &c), SDDPM_STATUS_OK);
  auto path = (std::filesystem::temp_directory_path() / ("sddpm_ctx_" + tag + ".obj")).string();
  ASSERT_EQ(sddpm_context_write_obj(c, 0, path.c_str()), SDDPM_STATUS_OK) << last_error();
  sddpm_context_free(c);
  SurfaceMesh sm;
  ASSERT_TRUE(CGAL::IO::read_OBJ(path, sm)) << tag;
  std::filesystem::remove(path);
  ASSERT_TRUE(sm.is_valid(false)) << tag;
  EXPECT_TRUE(CGAL::is_closed(sm)) << tag;
  auto fcc = sm.add_property_map<SurfaceMesh::Face_index, std::size_t>("f:cc").first;
  EXPECT_EQ(PMP::connected_components(sm, fcc), 1u) << tag;
  const long chi = static_cast<long>(sm.number_of_vertices()) - static_cast<long>(sm.number_of_edges()) +
                   static_cast<long>(sm.number_of_faces());
  EXPECT_EQ(m.genus, (2 - chi) / 2) << tag << ": CGAL V-E+F = " << chi;
  EXPECT_TRUE(PMP::is_outward_oriented(sm)) << tag;
  int vox = 0;
  for (int x : l) vox += subvoxels(x);
  EXPECT_NEAR(PMP::volume(sm), vox / 27.0, 1e-12) << tag;
}

}  // namespace

TEST(ContextCgal, SinglePrimitives) {
  for (int p = 1; p <= 10; ++p) {
    Labels l{};
    l[0] = p;
    Measured m = ours(l);
    EXPECT_TRUE(m.valid);
    EXPECT_EQ(m.genus, (p >= 2 && p <= 4) ? 1 : 0) << "label " << p;
    compare(l, "single" + std::to_string(p));
  }
}

TEST(ContextCgal, FullGrids) {
  // THC+Z / THC+X / THC+Y fill the grid with 6 / 4 / 6 separate holes (holes along
  // an axis join across cells); BHC grids seal the holes opening into a neighbour.
  const int64_t expect_genus[11] = {-1, 0, 6, 4, 6, -1, -1, -1, -1, -1, -1};
  for (int p = 1; p <= 10; ++p) {
    Labels l;
    l.fill(p);
    Measured m = ours(l);
    if (expect_genus[p] >= 0) {
      EXPECT_TRUE(m.valid) << "label " << p;
      EXPECT_EQ(m.genus, expect_genus[p]) << "label " << p;
    } else {
      EXPECT_FALSE(m.valid) << "label " << p << ": blind holes facing a neighbour are sealed cavities";
    }
    compare(l, "full" + std::to_string(p));
  }
}

TEST(ContextCgal, FiveHundredRandomValidContexts) {
  std::mt19937 rng(2024);
  int valid = 0, tried = 0;
  while (valid < 500) {
    ASSERT_LT(++tried, 200000);
    Labels l{};
    const int occupied = 1 + static_cast<int>(rng() % 12);
    for (int k = 0; k < occupied; ++k) l[rng() % 12] = 1 + static_cast<int>(rng() % 10);
    if (!ours(l).valid) continue;
    ++valid;
    compare(l, "random" + std::to_string(valid));
  }
}
