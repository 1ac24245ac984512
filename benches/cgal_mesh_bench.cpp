// CGAL side of the mesh-load benchmark: for each file, the median over
// repetitions of CGAL::IO::read_polygon_mesh into a Surface_mesh (CGAL reads
// the polygon soup, merges duplicate points, orients and builds the mesh),
// the Euler characteristic and PMP::volume. Prints CSV: file,seconds,chi,volume.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/IO/polygon_mesh_io.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<K::Point_3>;

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s REPEATS FILE...\n", argv[0]);
    return 2;
  }
  const int reps = std::max(1, std::atoi(argv[1]));
  std::printf("file,seconds,chi,volume\n");
  for (int a = 2; a < argc; ++a) {
    std::vector<double> times;
    long chi = 0;
    double vol = 0;
    for (int r = 0; r < reps; ++r) {
      auto t0 = std::chrono::steady_clock::now();
      SurfaceMesh sm;
      if (!CGAL::Polygon_mesh_processing::IO::read_polygon_mesh(argv[a], sm)) {
        std::fprintf(stderr, "CGAL cannot read %s\n", argv[a]);
        return 1;
      }
      chi = static_cast<long>(sm.number_of_vertices()) - static_cast<long>(sm.number_of_edges()) +
            static_cast<long>(sm.number_of_faces());
      vol = CGAL::Polygon_mesh_processing::volume(sm);
      times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    std::sort(times.begin(), times.end());
    std::string name = argv[a];
    name = name.substr(name.find_last_of('/') + 1);
    std::printf("%s,%.6f,%ld,%.17g\n", name.c_str(), times[times.size() / 2], chi, vol);
  }
  return 0;
}
