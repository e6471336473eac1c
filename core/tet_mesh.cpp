#include "core/tet_mesh.hpp"

#include <Eigen/Geometry>

namespace core {

double tet_volume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                  const Eigen::Vector3d& d) {
  return (b - a).cross(c - a).dot(d - a) / 6.0;
}

double TetMesh::volume() const {
  double v = 0.0;
  for (int t = 0; t < tets.rows(); ++t)
    v += tet_volume(vertices.row(tets(t, 0)), vertices.row(tets(t, 1)), vertices.row(tets(t, 2)),
                    vertices.row(tets(t, 3)));
  return v;
}

double TetMesh::tagged_area(FaceTag tag) const {
  double area = 0.0;
  for (int f = 0; f < boundary_faces.rows(); ++f) {
    if (face_tags[f] != tag) continue;
    const Eigen::Vector3d a = vertices.row(boundary_faces(f, 0));
    const Eigen::Vector3d b = vertices.row(boundary_faces(f, 1));
    const Eigen::Vector3d c = vertices.row(boundary_faces(f, 2));
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  return area;
}

}  // namespace core
