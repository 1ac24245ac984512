// VTK peer test of the hex exports: every VTU / legacy VTK file written by
// `cargo test --release --test hex_export` is read back with VTK's readers; node and
// element counts must match what the library wrote (NAME.counts), every cell must be a
// VTK_HEXAHEDRON, and vtkMeshQuality's hex scaled Jacobian must equal the library's
// per-element value (cell data "scaled_jacobian") to 1e-9.
#include <gtest/gtest.h>

#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDataArray.h>
#include <vtkMeshQuality.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>
#include <vtkUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <cfloat>
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#ifndef SDDPM_HEX_FIXTURES
#error "SDDPM_HEX_FIXTURES must name the folder the Rust test writes"
#endif

namespace {

const std::vector<std::string> kNames = {"zoo", "hole_level1", "hole_level1_mapped"};

std::string path(const std::string& name, const std::string& ext) {
  return std::string(SDDPM_HEX_FIXTURES) + "/" + name + "." + ext;
}

struct Counts {
  long nodes = -1, elements = -1;
};

Counts read_counts(const std::string& name) {
  Counts c;
  std::ifstream f(path(name, "counts"));
  f >> c.nodes >> c.elements;
  return c;
}

void check_grid(vtkUnstructuredGrid* g, const std::string& name, const std::string& what) {
  ASSERT_NE(g, nullptr) << what;
  const Counts c = read_counts(name);
  ASSERT_GE(c.nodes, 0) << "missing " << path(name, "counts");
  EXPECT_EQ(g->GetNumberOfPoints(), c.nodes) << what;
  ASSERT_EQ(g->GetNumberOfCells(), c.elements) << what;
  for (vtkIdType i = 0; i < g->GetNumberOfCells(); ++i) {
    ASSERT_EQ(g->GetCellType(i), VTK_HEXAHEDRON) << what << " cell " << i;
  }
  vtkDataArray* ours = g->GetCellData()->GetArray("scaled_jacobian");
  ASSERT_NE(ours, nullptr) << what << ": no cell data scaled_jacobian";
  ASSERT_EQ(ours->GetNumberOfTuples(), g->GetNumberOfCells());

  vtkNew<vtkMeshQuality> q;
  q->SetInputData(g);
  q->SetHexQualityMeasureToScaledJacobian();
  q->Update();
  vtkDataArray* theirs = vtkDataSet::SafeDownCast(q->GetOutput())->GetCellData()->GetArray("Quality");
  ASSERT_NE(theirs, nullptr);
  ASSERT_EQ(theirs->GetNumberOfTuples(), g->GetNumberOfCells());
  int negative = 0;
  for (vtkIdType i = 0; i < g->GetNumberOfCells(); ++i) {
    const double a = ours->GetTuple1(i), b = theirs->GetTuple1(i);
    if (b < 0) ++negative;
    if (a == DBL_MAX || b == DBL_MAX) {
      EXPECT_EQ(a, b) << what << " cell " << i;
    } else {
      EXPECT_NEAR(a, b, 1e-9) << what << " cell " << i;
    }
  }
  ::testing::Test::RecordProperty(what + "_negative", negative);
}

}  // namespace

TEST(VtkQuality, VtuFilesMatchVtkMeshQuality) {
  for (const auto& name : kNames) {
    vtkNew<vtkXMLUnstructuredGridReader> r;
    r->SetFileName(path(name, "vtu").c_str());
    r->Update();
    check_grid(r->GetOutput(), name, name + ".vtu");
  }
}

TEST(VtkQuality, LegacyVtkFilesMatchVtkMeshQuality) {
  for (const auto& name : kNames) {
    vtkNew<vtkUnstructuredGridReader> r;
    r->SetFileName(path(name, "vtk").c_str());
    r->Update();
    check_grid(r->GetOutput(), name, name + ".vtk");
  }
}

TEST(VtkQuality, ZooHasTheHandComputedValues) {
  vtkNew<vtkXMLUnstructuredGridReader> r;
  r->SetFileName(path("zoo", "vtu").c_str());
  r->Update();
  vtkNew<vtkMeshQuality> q;
  q->SetInputData(r->GetOutput());
  q->SetHexQualityMeasureToScaledJacobian();
  q->Update();
  vtkDataArray* v = vtkDataSet::SafeDownCast(q->GetOutput())->GetCellData()->GetArray("Quality");
  ASSERT_NE(v, nullptr);
  ASSERT_EQ(v->GetNumberOfTuples(), 5);
  EXPECT_NEAR(v->GetTuple1(0), 1.0, 1e-12);                          // unit cube
  EXPECT_NEAR(v->GetTuple1(1), 1.0 / std::sqrt(1.0 + 0.75 * 0.75), 1e-12);  // sheared
  EXPECT_NEAR(v->GetTuple1(2), 1.0 / std::sqrt(1.125), 1e-12);       // tapered
  EXPECT_NEAR(v->GetTuple1(3), 2.0 / (3.0 * std::sqrt(6.0)), 1e-12); // one corner pulled
  EXPECT_NEAR(v->GetTuple1(4), -1.0, 1e-12);                         // flipped node order
}

// The sampled spline (spline.vtu: binary, raw appended data) reads with VTK's XML
// reader: the counts written next to it, every cell a VTK_HEXAHEDRON, the point
// data "jacobian" and "scaled_jacobian" and the cell data "element" and "level".
TEST(VtkQuality, SplineVtuReadsWithVtk) {
  std::ifstream counts(std::string(SDDPM_HEX_FIXTURES) + "/spline_vtu.counts");
  ASSERT_TRUE(counts.good()) << "run cargo test --release --test hex_export first";
  long points = 0, cells = 0, elements = 0;
  counts >> points >> cells >> elements;
  vtkNew<vtkXMLUnstructuredGridReader> r;
  r->SetFileName((std::string(SDDPM_HEX_FIXTURES) + "/spline.vtu").c_str());
  r->Update();
  vtkUnstructuredGrid* g = r->GetOutput();
  ASSERT_EQ(g->GetNumberOfPoints(), points);
  ASSERT_EQ(g->GetNumberOfCells(), cells);
  for (vtkIdType i = 0; i < g->GetNumberOfCells(); ++i) {
    ASSERT_EQ(g->GetCellType(i), VTK_HEXAHEDRON) << "cell " << i;
  }
  for (const char* name : {"jacobian", "scaled_jacobian"}) {
    vtkDataArray* a = g->GetPointData()->GetArray(name);
    ASSERT_NE(a, nullptr) << name;
    ASSERT_EQ(a->GetNumberOfTuples(), points) << name;
  }
  vtkDataArray* sj = g->GetPointData()->GetArray("scaled_jacobian");
  for (vtkIdType i = 0; i < points; ++i) {
    EXPECT_GT(sj->GetTuple1(i), 0.0) << "point " << i;
    EXPECT_LE(sj->GetTuple1(i), 1.0 + 1e-6) << "point " << i;
  }
  vtkDataArray* element = g->GetCellData()->GetArray("element");
  ASSERT_NE(element, nullptr);
  ASSERT_NE(g->GetCellData()->GetArray("level"), nullptr);
  EXPECT_EQ(element->GetTuple1(cells - 1), elements - 1);
}
