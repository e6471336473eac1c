#include "meshless/verification/box_mesh.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <random>
#include <stdexcept>
#include <vector>

namespace meshless {

core::TetMesh make_box_mesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int nx, int ny, int nz,
                            const FaceTagger& tagger, double jitter, unsigned seed) {
  if (nx < 1 || ny < 1 || nz < 1) throw std::invalid_argument("make_box_mesh: need at least one cell per axis");
  if (!(jitter >= 0.0 && jitter < 0.25)) throw std::invalid_argument("make_box_mesh: jitter must be in [0, 0.25)");
  const std::array<int, 3> n = {nx, ny, nz};
  const Eigen::Vector3d h = (hi - lo).cwiseQuotient(Eigen::Vector3d(nx, ny, nz));
  auto id = [&](int i, int j, int k) { return (i * (ny + 1) + j) * (nz + 1) + k; };

  core::TetMesh m;
  m.vertices.resize((nx + 1) * (ny + 1) * (nz + 1), 3);
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  for (int i = 0; i <= nx; ++i)
    for (int j = 0; j <= ny; ++j)
      for (int k = 0; k <= nz; ++k) {
        const std::array<int, 3> ijk = {i, j, k};
        Eigen::Vector3d x;
        for (int d = 0; d < 3; ++d) {
          const bool boundary = ijk[d] == 0 || ijk[d] == n[d];
          x[d] = lo[d] + h[d] * (ijk[d] + (boundary || jitter == 0.0 ? 0.0 : u(gen)));
        }
        m.vertices.row(id(i, j, k)) = x.transpose();
      }

  // Six tets per hex: corner 0 -> corner 7 along every permutation of the axes.
  static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  m.tets.resize(6 * nx * ny * nz, 4);
  int t = 0;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k)
        for (const auto& p : perms) {
          std::array<int, 3> c = {i, j, k};
          std::array<int, 4> v;
          v[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[p[s]];
            v[s + 1] = id(c[0], c[1], c[2]);
          }
          const double vol = core::tet_volume(m.vertices.row(v[0]), m.vertices.row(v[1]), m.vertices.row(v[2]),
                                              m.vertices.row(v[3]));
          if (vol < 0.0) std::swap(v[2], v[3]);
          m.tets.row(t++) << v[0], v[1], v[2], v[3];
        }

  // Boundary: two triangles per boundary quad, oriented along the outward axis normal.
  std::vector<std::array<int, 3>> faces;
  std::vector<core::FaceTag> tags;
  for (int d = 0; d < 3; ++d) {
    const int d1 = (d + 1) % 3, d2 = (d + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      Eigen::Vector3d normal = Eigen::Vector3d::Zero();
      normal[d] = side == 0 ? -1.0 : 1.0;
      for (int a = 0; a < n[d1]; ++a)
        for (int b = 0; b < n[d2]; ++b) {
          std::array<int, 4> q;
          const int corners[4][2] = {{a, b}, {a + 1, b}, {a + 1, b + 1}, {a, b + 1}};
          for (int c = 0; c < 4; ++c) {
            std::array<int, 3> ijk;
            ijk[d] = side == 0 ? 0 : n[d];
            ijk[d1] = corners[c][0];
            ijk[d2] = corners[c][1];
            q[c] = id(ijk[0], ijk[1], ijk[2]);
          }
          for (const std::array<int, 3>& tri : {std::array<int, 3>{q[0], q[1], q[2]}, std::array<int, 3>{q[0], q[2], q[3]}}) {
            std::array<int, 3> f = tri;
            const Eigen::Vector3d p0 = m.vertices.row(f[0]), p1 = m.vertices.row(f[1]), p2 = m.vertices.row(f[2]);
            if ((p1 - p0).cross(p2 - p0).dot(normal) < 0.0) std::swap(f[1], f[2]);
            faces.push_back(f);
            const Eigen::Vector3d centroid = (p0 + p1 + p2) / 3.0;
            tags.push_back(tagger ? tagger(centroid, normal) : core::FaceTag::free_surface);
          }
        }
    }
  }
  m.boundary_faces.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f) m.boundary_faces.row(static_cast<Eigen::Index>(f)) << faces[f][0], faces[f][1], faces[f][2];
  m.face_tags = tags;
  m.vertex_fixed.assign(m.vertices.rows(), 0);
  for (size_t f = 0; f < faces.size(); ++f)
    if (tags[f] == core::FaceTag::fixed)
      for (int v : faces[f]) m.vertex_fixed[v] = 1;
  return m;
}

}  // namespace meshless
