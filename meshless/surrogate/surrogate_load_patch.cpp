#include "meshless/surrogate/surrogate_load_patch.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <limits>
#include <stdexcept>

namespace meshless {

int SurfaceNodes::nearest(const Eigen::Vector3d& x, double* distance) const {
  // A linear scan: called once per contact point at set-up, never in the haptic loop.
  int best = -1;
  double best_sq = std::numeric_limits<double>::infinity();
  for (int s = 0; s < size(); ++s) {
    const double d = (position.row(s).transpose() - x).squaredNorm();
    if (d < best_sq) {
      best_sq = d;
      best = s;
    }
  }
  if (best < 0) throw std::invalid_argument("SurfaceNodes::nearest: the cloud has no surface node");
  if (distance) *distance = std::sqrt(best_sq);
  return best;
}

SurfaceNodes surface_nodes(const core::TetMesh& mesh) {
  const int nv = mesh.num_vertices();
  Eigen::MatrixX3d area_normal = Eigen::MatrixX3d::Zero(nv, 3);
  std::vector<char> on_surface(nv, 0);
  for (Eigen::Index f = 0; f < mesh.boundary_faces.rows(); ++f) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.boundary_faces(f, 0));
    const Eigen::Vector3d b = mesh.vertices.row(mesh.boundary_faces(f, 1));
    const Eigen::Vector3d c = mesh.vertices.row(mesh.boundary_faces(f, 2));
    const Eigen::Vector3d twice_area_normal = (b - a).cross(c - a);  // outward, |.| = 2 area
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.boundary_faces(f, k);
      area_normal.row(v) += twice_area_normal.transpose();
      on_surface[v] = 1;
    }
  }
  SurfaceNodes s;
  for (int v = 0; v < nv; ++v)
    if (on_surface[v]) s.vertex.push_back(v);
  s.position.resize(s.size(), 3);
  s.normal.resize(s.size(), 3);
  for (int i = 0; i < s.size(); ++i) {
    s.position.row(i) = mesh.vertices.row(s.vertex[i]);
    s.normal.row(i) = area_normal.row(s.vertex[i]).normalized();
  }
  return s;
}

LoadPatch load_patch(const core::TetMesh& mesh, const Eigen::Vector3d& contact, const Eigen::Vector3d& normal,
                     double radius) {
  const Eigen::Index nf = mesh.boundary_faces.rows();
  LoadPatch p;
  p.faces.assign(nf, 0);
  for (Eigen::Index f = 0; f < nf; ++f) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.boundary_faces(f, 0));
    const Eigen::Vector3d b = mesh.vertices.row(mesh.boundary_faces(f, 1));
    const Eigen::Vector3d c = mesh.vertices.row(mesh.boundary_faces(f, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a);
    if (((a + b + c) / 3.0 - contact).norm() > radius || n.dot(normal) <= 0.0) continue;
    p.faces[f] = 1;
    p.area += 0.5 * n.norm();
    ++p.num_faces;
  }
  if (p.num_faces == 0)
    throw std::invalid_argument(fmt::format(
        "no boundary face has its centroid within {:.3g} mm of the contact node ({:.4g}, {:.4g}, {:.4g}) mm; "
        "expected a patch radius larger than the local face size",
        radius * 1e3, contact.x() * 1e3, contact.y() * 1e3, contact.z() * 1e3));
  return p;
}

double smooth_profile(double distance, double radius) {
  const double x = distance / radius;
  return x < 1.0 ? (1.0 - x * x) * (1.0 - x * x) : 0.0;
}

SmoothLoadPatch smooth_load_patch(const core::TetMesh& mesh, const QuadraturePoints& boundary,
                                  const Eigen::Vector3d& contact, const Eigen::Vector3d& normal, double radius) {
  const Eigen::Index nf = mesh.boundary_faces.rows();
  std::vector<char> side(nf, 0);
  for (Eigen::Index f = 0; f < nf; ++f) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.boundary_faces(f, 0));
    const Eigen::Vector3d b = mesh.vertices.row(mesh.boundary_faces(f, 1));
    const Eigen::Vector3d c = mesh.vertices.row(mesh.boundary_faces(f, 2));
    side[f] = (b - a).cross(c - a).dot(normal) > 0.0;
  }
  SmoothLoadPatch p;
  p.faces.assign(nf, 0);
  for (int q = 0; q < boundary.size(); ++q) {
    if (boundary.on_lip(q)) continue;  // the lips of a cut are never loaded (EfgProblem::loaded_faces)
    const int f = boundary.cells[q];
    const double w = smooth_profile((boundary.points.row(q).transpose() - contact).norm(), radius);
    if (w <= 0.0 || !side[f]) continue;
    if (!p.faces[f]) ++p.num_faces;
    p.faces[f] = 1;
    p.profile_integral += boundary.weights[q] * w;
  }
  // Every point of a loaded face counts, in the model's quadrature: the profile is 0 at those beyond R.
  if (p.num_faces == 0)
    throw std::invalid_argument(fmt::format(
        "no boundary quadrature point lies within {:.3g} mm of the contact node ({:.4g}, {:.4g}, {:.4g}) mm; "
        "expected a patch radius larger than the local face size",
        radius * 1e3, contact.x() * 1e3, contact.y() * 1e3, contact.z() * 1e3));
  return p;
}

}  // namespace meshless
