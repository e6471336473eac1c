#include "core/tet_point_location.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace core {
namespace {

constexpr double kInside = 1e-10;  // barycentric slack for a point on a face shared by two tets
constexpr double kOnCrack = 1e-6;  // [m] Gmsh puts the crack's nodes on its planes to round-off (as sample_evaluator)

Eigen::Vector3d vertex(const TetMesh& mesh, int t, int k) { return mesh.vertices.row(mesh.tets(t, k)).transpose(); }

Eigen::Vector4d barycentric(const TetMesh& mesh, int t, const Eigen::Vector3d& x) {
  const Eigen::Vector3d a = vertex(mesh, t, 0);
  Eigen::Matrix3d edges;
  for (int k = 0; k < 3; ++k) edges.col(k) = vertex(mesh, t, k + 1) - a;
  const Eigen::Vector3d l = edges.partialPivLu().solve(x - a);
  return Eigen::Vector4d(1.0 - l.sum(), l(0), l(1), l(2));
}

/// Whether tet t may hold a point on lip `side`: no vertex, nor the centroid, lies behind the front on the other side.
bool on_lip(const TetMesh& mesh, const RuledSurface& cut, int t, int side) {
  auto other_side = [&](const Eigen::Vector3d& p) {
    const CutFrame f = cut.frame(p);
    return f.behind_front && std::abs(f.s) > kOnCrack && (f.s > 0 ? 1 : -1) != side;
  };
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (int k = 0; k < 4; ++k) {
    if (other_side(vertex(mesh, t, k))) return false;
    centroid += 0.25 * vertex(mesh, t, k);
  }
  return !other_side(centroid);
}

}  // namespace

std::vector<TetPointLocation> locate_points(const TetMesh& mesh, const PointMatrix& points, double tolerance,
                                            const RuledSurface* cut) {
  std::vector<TetPointLocation> locations;
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const Eigen::Vector3d x = points.row(i).transpose();
    const bool lip_rule = cut && cut->frame(x).behind_front;
    const int side = lip_rule ? cut->side(x) : 0;
    auto allowed = [&](int t) { return !lip_rule || on_lip(mesh, *cut, t, side); };
    TetPointLocation best;
    best.offset = std::numeric_limits<double>::infinity();
    for (int t = 0; t < mesh.num_tets() && best.offset > 0.0; ++t) {
      const Eigen::Vector4d l = barycentric(mesh, t, x);
      if (l.minCoeff() >= -kInside) {
        if (!allowed(t)) continue;
        best.tet = t;
        best.barycentric = l.cwiseMax(0.0) / l.cwiseMax(0.0).sum();
        best.offset = 0.0;
        continue;
      }
      // Outside this tet: the nearest point of it, as the reference projects (clamp, renormalise).
      const Eigen::Vector4d clamped = l.cwiseMax(0.0) / l.cwiseMax(0.0).sum();
      Eigen::Vector3d y = Eigen::Vector3d::Zero();
      for (int k = 0; k < 4; ++k) y += clamped(k) * vertex(mesh, t, k);
      const double d = (y - x).norm();
      if (d < best.offset && allowed(t)) {
        best.tet = t;
        best.barycentric = clamped;
        best.offset = d;
      }
    }
    if (best.tet < 0 || best.offset > tolerance)
      throw std::runtime_error(fmt::format("point {} at ({:.3f}, {:.3f}, {:.3f}) mm lies {:.3f} mm outside the mesh{} "
                                           "(tolerance {:.3f} mm)",
                                           i, x.x() * 1e3, x.y() * 1e3, x.z() * 1e3, best.offset * 1e3,
                                           lip_rule ? " on its lip of the cut" : "", tolerance * 1e3));
    locations.push_back(best);
  }
  return locations;
}

}  // namespace core
