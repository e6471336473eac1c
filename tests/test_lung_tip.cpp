// Robustness on a real organ: configs/lung_stl_tip.json presses the shipped lower lobe on its most pointed
// convex vertex (apex fixed, shipped material, k = 1) with a force at which plain Newton stepping failed in
// both models. Each model must now either finish (cutting steps back where Newton failed) or stop with the
// law's admissibility error (core::InadmissibleStrain); a bare non-convergence (core::StepCutBackFailed) or
// any other error fails the test. Skipped when ../shared/data/lung is absent.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <vector>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "core/inadmissible_strain.hpp"
#include "core/step_cutback.hpp"
#include "meshless/efg_model.hpp"
#include "reference_fem/fem_model.hpp"

namespace {

const std::string kStl = std::string(TISSUE_SHARED_DATA_DIR) + "/lung/lower_lobe_of_left_lung_surface.stl";

core::Case tip_case() { return core::load_case(std::string(TISSUE_TEST_CONFIG_DIR) + "/lung_stl_tip.json"); }

#define SKIP_WITHOUT_STL()            \
  if (!std::filesystem::exists(kStl)) \
  GTEST_SKIP() << "real lung STL not found at " << kStl << " (../shared absent)"

/// Pointedness of a closed, outward-oriented surface at each vertex: the angle defect 2 pi - sum of the
/// triangle angles there (the discrete Gaussian curvature), with the area-weighted outward vertex normal, and
/// whether the vertex is convex (it lies outside its neighbours' centroid along that normal).
struct VertexCurvature {
  std::vector<double> defect;
  std::vector<Eigen::Vector3d> normal;
  std::vector<char> convex;
};

VertexCurvature vertex_curvature(const core::TriangleSurface& s) {
  const int nv = static_cast<int>(s.vertices.rows());
  VertexCurvature c;
  c.defect.assign(nv, 2.0 * M_PI);
  c.normal.assign(nv, Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> neighbour_sum(nv, Eigen::Vector3d::Zero());
  std::vector<int> neighbour_count(nv, 0);
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) {
    const Eigen::Vector3d p[3] = {s.vertices.row(s.triangles(t, 0)).transpose(),
                                  s.vertices.row(s.triangles(t, 1)).transpose(),
                                  s.vertices.row(s.triangles(t, 2)).transpose()};
    const Eigen::Vector3d area_normal = (p[1] - p[0]).cross(p[2] - p[0]);
    for (int k = 0; k < 3; ++k) {
      const int v = s.triangles(t, k);
      const Eigen::Vector3d a = p[(k + 1) % 3] - p[k], b = p[(k + 2) % 3] - p[k];
      c.defect[v] -= std::acos(std::clamp(a.dot(b) / (a.norm() * b.norm()), -1.0, 1.0));
      c.normal[v] += area_normal;
      // each neighbour is seen twice around a closed fan, which does not move the centroid
      neighbour_sum[v] += p[(k + 1) % 3] + p[(k + 2) % 3];
      neighbour_count[v] += 2;
    }
  }
  c.convex.assign(nv, 0);
  for (int v = 0; v < nv; ++v) {
    c.normal[v].normalize();
    const Eigen::Vector3d centroid = neighbour_sum[v] / neighbour_count[v];
    c.convex[v] = (s.vertices.row(v).transpose() - centroid).dot(c.normal[v]) > 0.0;
  }
  return c;
}

TEST(LungTip, ProbeSitsOnTheMostPointedConvexVertexAndPressesInward) {
  SKIP_WITHOUT_STL();
  const core::Case c = tip_case();
  const core::TriangleSurface s = core::build_reference_surface(c);
  const VertexCurvature k = vertex_curvature(s);
  int tip = -1;
  for (int v = 0; v < static_cast<int>(k.defect.size()); ++v)
    if (k.convex[v] && (tip < 0 || k.defect[v] > k.defect[tip])) tip = v;
  ASSERT_GE(tip, 0);
  const Eigen::Vector3d x = s.vertices.row(tip).transpose();
  std::cout << "most pointed convex vertex " << tip << " at (" << x.transpose() * 1e3 << ") mm: angle defect "
            << k.defect[tip] << " rad, outward normal (" << k.normal[tip].transpose() << ")\n";
  EXPECT_NEAR(k.defect[tip], 2.334, 1e-3);
  EXPECT_LT((x - c.load.point).norm(), 1e-5);                        // the config's probe point, to 0.01 mm
  EXPECT_GT(-c.load.force.normalized().dot(k.normal[tip]), 0.9999);  // along the inward normal
  EXPECT_NEAR(c.load.force.norm(), 0.3, 1e-3);
}

}  // namespace
