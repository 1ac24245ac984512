// Helpers shared by the C++ peer tests: the test meshes, and a mesh read through the C ABI.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "sddpm.h"

namespace sddpm_test {

inline std::string data_dir() { return SDDPM_TEST_DATA; }

// Every mesh file directly in tests/data/meshes (not bad/), sorted.
inline std::vector<std::string> good_meshes() {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(data_dir())) {
    if (!e.is_regular_file()) continue;
    auto ext = e.path().extension().string();
    if (ext == ".off" || ext == ".obj" || ext == ".stl") names.push_back(e.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

inline std::string test_name(const testing::TestParamInfo<std::string>& info) {
  std::string s = info.param;
  for (char& c : s)
    if (!isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

inline std::string last_error() {
  size_t needed = 0;
  sddpm_last_error_message(nullptr, 0, &needed);
  std::string buf(needed, '\0');
  if (sddpm_last_error_message(buf.data(), buf.size(), nullptr) != SDDPM_STATUS_OK) return "<no message>";
  buf.resize(needed ? needed - 1 : 0);
  return buf;
}

// A mesh as libsddpm welded it, copied out through the C ABI.
struct Loaded {
  sddpm_mesh_report report{};
  std::vector<double> xyz;
  std::vector<uint32_t> tri;
};

inline Loaded load(const std::string& name) {
  Loaded out;
  sddpm_mesh* m = nullptr;
  std::string path = data_dir() + "/" + name;
  sddpm_status s = sddpm_mesh_load(path.c_str(), nullptr, &m);
  EXPECT_EQ(s, SDDPM_STATUS_OK) << last_error();
  if (s != SDDPM_STATUS_OK) return out;
  EXPECT_EQ(sddpm_mesh_check(m, &out.report), SDDPM_STATUS_OK) << last_error();
  size_t nv = 0, nt = 0;
  EXPECT_EQ(sddpm_mesh_counts(m, &nv, &nt), SDDPM_STATUS_OK);
  out.xyz.resize(3 * nv);
  out.tri.resize(3 * nt);
  EXPECT_EQ(sddpm_mesh_copy_vertices(m, out.xyz.data(), out.xyz.size()), SDDPM_STATUS_OK) << last_error();
  EXPECT_EQ(sddpm_mesh_copy_triangles(m, out.tri.data(), out.tri.size()), SDDPM_STATUS_OK) << last_error();
  sddpm_mesh_free(m);
  return out;
}

inline double rel_err(double a, double b) { return std::abs(a - b) / std::max(std::abs(b), 1e-300); }

}  // namespace sddpm_test
