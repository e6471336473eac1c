#pragma once
// A linear tetrahedral mesh with tagged boundary triangles: the geometry object handed to both models.
#include <Eigen/Core>
#include <vector>

namespace core {

using PointMatrix = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;  ///< #points by 3, metres
using TetMatrix = Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>;       ///< #tets by 4, vertex ids
using TriMatrix = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;       ///< #faces by 3, vertex ids

/// What a boundary triangle is for.
enum class FaceTag : int {
  free_surface = 0,  ///< traction-free
  fixed = 1,         ///< essential BC: u = 0 (Dirichlet in FEM, penalty eq. 23 in EFG)
  load = 2,          ///< load patch: uniform traction = force / patch area
  crack = 3,         ///< a face of the duplicated cut surface (FEM reference only)
};

struct TetMesh {
  PointMatrix vertices;          ///< #V by 3 [m]
  TetMatrix tets;                ///< #T by 4, positively oriented
  TriMatrix boundary_faces;      ///< #F by 3, outward normal by right-hand rule
  std::vector<FaceTag> face_tags;     ///< #F
  std::vector<char> vertex_fixed;     ///< #V, 1 when the vertex lies in the fixed region

  int num_vertices() const { return static_cast<int>(vertices.rows()); }
  int num_tets() const { return static_cast<int>(tets.rows()); }
  double volume() const;                       ///< sum of tet volumes [m^3]
  double tagged_area(FaceTag tag) const;       ///< area of the faces carrying `tag` [m^2]
};

double tet_volume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                  const Eigen::Vector3d& d);

}  // namespace core
