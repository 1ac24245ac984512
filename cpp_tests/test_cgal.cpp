// Our genus, closedness, Euler characteristic and volume against CGAL 5.5 on
// every test mesh. CGAL sees the surface exactly as libsddpm welded it (copied
// out through the C ABI), so both measure the same triangles.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/helpers.h>

#include "common.hpp"

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<K::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;
using namespace sddpm_test;

class CgalPeer : public testing::TestWithParam<std::string> {};

TEST_P(CgalPeer, GenusClosednessAndVolume) {
  Loaded m = load(GetParam());
  ASSERT_FALSE(m.tri.empty());
  SurfaceMesh sm;
  std::vector<SurfaceMesh::Vertex_index> vs;
  for (size_t i = 0; i < m.xyz.size(); i += 3) vs.push_back(sm.add_vertex(K::Point_3(m.xyz[i], m.xyz[i + 1], m.xyz[i + 2])));
  for (size_t t = 0; t < m.tri.size(); t += 3) {
    auto f = sm.add_face(vs[m.tri[t]], vs[m.tri[t + 1]], vs[m.tri[t + 2]]);
    ASSERT_NE(f, SurfaceMesh::null_face()) << "CGAL refused triangle " << t / 3;
  }
  ASSERT_TRUE(sm.is_valid(false));

  const bool closed = CGAL::is_closed(sm);
  EXPECT_EQ(static_cast<bool>(m.report.closed), closed);
  const long chi = static_cast<long>(sm.number_of_vertices()) - static_cast<long>(sm.number_of_edges()) +
                   static_cast<long>(sm.number_of_faces());
  EXPECT_EQ(m.report.euler_characteristic, chi);
  auto fcc = sm.add_property_map<SurfaceMesh::Face_index, std::size_t>("f:cc").first;
  const std::size_t components = PMP::connected_components(sm, fcc);
  EXPECT_EQ(m.report.components, components);
  ASSERT_EQ(components, 1u);
  ASSERT_TRUE(closed);
  const long genus = (2 - chi) / 2;
  EXPECT_EQ(m.report.genus, genus) << "CGAL: V-E+F = " << chi;
  EXPECT_TRUE(PMP::is_outward_oriented(sm));

  const double v = PMP::volume(sm);
  EXPECT_LT(rel_err(m.report.volume, v), 1e-9) << "ours " << m.report.volume << " CGAL " << v;
  const double a = PMP::area(sm);
  EXPECT_LT(rel_err(m.report.area, a), 1e-9) << "ours " << m.report.area << " CGAL " << a;
}

INSTANTIATE_TEST_SUITE_P(Meshes, CgalPeer, testing::ValuesIn(good_meshes()), test_name);
