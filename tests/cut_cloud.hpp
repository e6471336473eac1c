#pragma once
// The cut test cloud shared by tests/test_efg_cut.cpp and tests/test_cut_weights.cpp: a jittered 11^3 box cloud
// (0.1 m edge, 10 mm spacing), its MLS shape functions, and a kinked incision's weights installed on them.
#include <Eigen/Core>
#include <memory>

#include "core/ruled_surface.hpp"
#include "meshless/cut/cut_weights.hpp"
#include "meshless/mls/mls_shape_functions.hpp"
#include "meshless/mls/node_search.hpp"
#include "meshless/mls/support_radii.hpp"
#include "meshless/verification/box_mesh.hpp"

namespace meshless::test {

constexpr double kCutBoxEdge = 0.1;  // [m] the box

/// A kinked incision from the top face z = 0.1 down 30 mm, three panels (turns of about 35 and 50 degrees).
inline core::RuledSurface kinked_cut() {
  return core::RuledSurface({Eigen::Vector3d(0.02, 0.05, 0.1), Eigen::Vector3d(0.045, 0.035, 0.1),
                             Eigen::Vector3d(0.07, 0.045, 0.1), Eigen::Vector3d(0.085, 0.07, 0.1)},
                            -Eigen::Vector3d::UnitZ(), 0.03);
}

/// MLS over the jittered 11^3 box cloud with the kinked cut's weights installed (d_max 2, k 6).
struct CutCloud {
  core::TetMesh mesh;
  std::unique_ptr<NodeSearch> search;
  std::unique_ptr<SupportRadii> radii;
  std::unique_ptr<MlsShapeFunctions> mls;
  std::unique_ptr<CutWeights> weights;

  CutCloud(CutTreatment treatment, double transition) {
    mesh = make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(kCutBoxEdge), 10, 10, 10, {}, 0.2, 17);
    search = std::make_unique<NodeSearch>(mesh.vertices);
    SupportRadiiParams p;
    p.d_max = 2.0;
    p.k = 6;
    radii = std::make_unique<SupportRadii>(mesh.vertices, *search, p);
    mls = std::make_unique<MlsShapeFunctions>(mesh.vertices, *radii, *search);
    weights = std::make_unique<CutWeights>(kinked_cut(), mesh.vertices, radii->radii(), treatment, transition);
    const CutWeights* w = weights.get();
    mls->set_weight_modifier(
        [w](int i, const Eigen::Vector3d& x, int side, Eigen::Vector3d* g) { return (*w)(i, x, side, g); });
  }
  Eigen::Vector3d node(int i) const { return mesh.vertices.row(i).transpose(); }
};

}  // namespace meshless::test
