// core::order_for_locality: a permutation of the mesh (same cells, faces, tags, orientation) that brings
// neighbours close in number, as the EFG assembly's cache use needs (core/mesh_ordering.hpp).
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <numeric>
#include <random>
#include <set>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "core/mesh_ordering.hpp"
#include "meshless/verification/box_mesh.hpp"

namespace {

/// A 12^3-cell box with tagged faces, numbered at random (as Gmsh's insertion order scatters neighbours).
core::TetMesh scrambled_box() {
  core::TetMesh mesh = meshless::make_box_mesh(
      Eigen::Vector3d::Zero(), Eigen::Vector3d(0.03, 0.02, 0.04), 12, 12, 12,
      [](const Eigen::Vector3d& c, const Eigen::Vector3d&) {
        return c.z() < 1e-9 ? core::FaceTag::fixed : (c.z() > 0.04 - 1e-9 ? core::FaceTag::load : core::FaceTag::free_surface);
      },
      0.2, 7);
  mesh.vertex_fixed.assign(mesh.num_vertices(), 0);
  for (int v = 0; v < mesh.num_vertices(); ++v) mesh.vertex_fixed[v] = mesh.vertices(v, 2) < 1e-9;
  std::vector<int> perm(mesh.num_vertices());
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), std::mt19937(3));  // new number of old vertex v: perm[v]
  core::TetMesh out = mesh;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    out.vertices.row(perm[v]) = mesh.vertices.row(v);
    out.vertex_fixed[perm[v]] = mesh.vertex_fixed[v];
  }
  for (int t = 0; t < mesh.num_tets(); ++t)
    for (int k = 0; k < 4; ++k) out.tets(t, k) = perm[mesh.tets(t, k)];
  for (int f = 0; f < mesh.boundary_faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) out.boundary_faces(f, k) = perm[mesh.boundary_faces(f, k)];
  return out;
}

/// Mean |i - j| over the edges of the tetrahedra: how far apart in memory neighbours are.
double mean_edge_span(const core::TetMesh& mesh) {
  double sum = 0.0;
  for (int t = 0; t < mesh.num_tets(); ++t)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) sum += std::abs(mesh.tets(t, a) - mesh.tets(t, b));
  return sum / (6.0 * mesh.num_tets());
}

/// Each cell as the sorted coordinates of its vertices, and whether it is positive: independent of numbering.
std::multiset<std::array<double, 13>> cells_by_coordinates(const core::TetMesh& mesh) {
  std::multiset<std::array<double, 13>> cells;
  for (int t = 0; t < mesh.num_tets(); ++t) {
    std::array<std::array<double, 3>, 4> v;
    for (int k = 0; k < 4; ++k) v[k] = {mesh.vertices(mesh.tets(t, k), 0), mesh.vertices(mesh.tets(t, k), 1),
                                        mesh.vertices(mesh.tets(t, k), 2)};
    const double volume = core::tet_volume(mesh.vertices.row(mesh.tets(t, 0)), mesh.vertices.row(mesh.tets(t, 1)),
                                           mesh.vertices.row(mesh.tets(t, 2)), mesh.vertices.row(mesh.tets(t, 3)));
    std::sort(v.begin(), v.end());
    std::array<double, 13> key{};
    for (int k = 0; k < 4; ++k)
      for (int d = 0; d < 3; ++d) key[3 * k + d] = v[k][d];
    key[12] = volume > 0.0 ? 1.0 : -1.0;
    cells.insert(key);
  }
  return cells;
}

TEST(MeshOrdering, IsAPermutationKeepingCellsFacesTagsAndOrientation) {
  const core::TetMesh before = scrambled_box();
  core::TetMesh after = before;
  const std::vector<int> new_index = core::order_for_locality(&after);

  // new_index is a permutation, and the vertices moved with it.
  std::vector<int> sorted = new_index;
  std::sort(sorted.begin(), sorted.end());
  for (int v = 0; v < before.num_vertices(); ++v) ASSERT_EQ(sorted[v], v);
  for (int v = 0; v < before.num_vertices(); ++v) {
    EXPECT_EQ(after.vertices.row(new_index[v]), before.vertices.row(v));
    EXPECT_EQ(after.vertex_fixed[new_index[v]], before.vertex_fixed[v]);
  }
  // The same cells, all still positive; the same volume and tagged areas; every face keeps its tag.
  EXPECT_EQ(cells_by_coordinates(after), cells_by_coordinates(before));
  for (const auto& key : cells_by_coordinates(after)) EXPECT_EQ(key[12], 1.0);
  EXPECT_NEAR(after.volume(), before.volume(), 1e-16);  // Measured 1.7e-19 (of 2.4e-5 m^3)
  for (core::FaceTag tag : {core::FaceTag::fixed, core::FaceTag::load, core::FaceTag::free_surface})
    EXPECT_NEAR(after.tagged_area(tag), before.tagged_area(tag), 1e-15);
  std::multiset<std::pair<std::array<int, 3>, int>> faces_before, faces_after;
  for (int f = 0; f < before.boundary_faces.rows(); ++f) {
    faces_before.insert({{new_index[before.boundary_faces(f, 0)], new_index[before.boundary_faces(f, 1)],
                          new_index[before.boundary_faces(f, 2)]},
                         static_cast<int>(before.face_tags[f])});
    faces_after.insert({{after.boundary_faces(f, 0), after.boundary_faces(f, 1), after.boundary_faces(f, 2)},
                        static_cast<int>(after.face_tags[f])});
  }
  EXPECT_EQ(faces_after, faces_before);  // same vertex order within each face: same outward normal
}

TEST(MeshOrdering, BringsNeighboursCloseInNumber) {
  core::TetMesh mesh = scrambled_box();
  const double scrambled = mean_edge_span(mesh);
  core::order_for_locality(&mesh);
  const double ordered = mean_edge_span(mesh);
  // 2,197 vertices: at random a neighbour is about a third of the mesh away (~730); by reverse Cuthill–McKee about
  // one level of the breadth-first search (measured 72, against 733).
  std::cout << "mean |i - j| over tet edges: scrambled " << scrambled << ", ordered " << ordered << "\n";
  EXPECT_LT(ordered, scrambled / 8.0);
  // The cells follow their vertices (sorted by their smallest), so the integration points, made cell by cell, do.
  for (int t = 1; t < mesh.num_tets(); ++t) ASSERT_LE(mesh.tets.row(t - 1).minCoeff(), mesh.tets.row(t).minCoeff());
}

TEST(MeshOrdering, TheShippedCloudIsOrderedAndGmshLeavesTheThreadCountAlone) {
  // Gmsh's General.NumThreads = 1 sets the process's OpenMP thread count; the session restores it, or the EFG
  // model's loops after the meshing run on one core (core/gmsh_session.hpp).
  omp_set_num_threads(3);
  const core::Case c = core::load_case(std::string(TISSUE_TEST_CONFIG_DIR) + "/ci/lung_small_ci.json");
  core::GeometryOptions options;
  options.build_fem_mesh = false;
  const core::Geometry g = core::build_geometry(c, options);
  EXPECT_EQ(omp_get_max_threads(), 3);
  // The node cloud comes numbered for locality: ordering it again changes little.
  core::TetMesh again = g.meshless_mesh;
  const double shipped = mean_edge_span(g.meshless_mesh);
  core::order_for_locality(&again);
  std::cout << "lung_small_ci cloud: mean |i - j| over tet edges " << shipped << " (" << g.meshless_mesh.num_vertices()
            << " nodes)\n";
  EXPECT_LT(shipped, 1.05 * mean_edge_span(again));
  EXPECT_LT(shipped, 0.05 * g.meshless_mesh.num_vertices());
}

}  // namespace
