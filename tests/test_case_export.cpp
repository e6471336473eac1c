// `tissue export` read back (label geometry, seconds): the exported mesh is the FEM reference's mesh raised to second
// order, with the sets it claims, and the CalculiX deck's nodal forces sum to the case's force
// (experiments/export/case_export.hpp, docs/FEM_REFERENCE.md "An independent FE code: CalculiX").
#include <gmsh.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "core/gmsh_session.hpp"
#include "core/output_directory.hpp"
#include "experiments/export/case_export.hpp"

namespace experiments {
namespace {

constexpr int kGmshTriangle6 = 9, kGmshTet10 = 11;

/// Elements of `type` in the physical group called `name` of dimension `dim` of the open Gmsh model.
std::size_t elements_in_group(int dim, const std::string& name, int type) {
  gmsh::vectorpair groups;
  gmsh::model::getPhysicalGroups(groups, dim);
  for (const auto& [d, tag] : groups) {
    std::string group_name;
    gmsh::model::getPhysicalName(d, tag, group_name);
    if (group_name != name) continue;
    std::vector<int> entities;
    gmsh::model::getEntitiesForPhysicalGroup(d, tag, entities);
    std::size_t n = 0;
    for (const int e : entities) {
      std::vector<std::size_t> element_tags, node_tags;
      gmsh::model::mesh::getElementsByType(type, element_tags, node_tags, e);
      n += element_tags.size();
    }
    return n;
  }
  ADD_FAILURE() << "no physical group " << name << " of dimension " << dim;
  return 0;
}

/// The sum of the *CLOAD lines of a CalculiX deck [N].
Eigen::Vector3d cload_sum(const std::filesystem::path& deck) {
  std::ifstream in(deck);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  std::string line;
  bool in_cload = false;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] == '*') {
      in_cload = line.rfind("*CLOAD", 0) == 0;
      continue;
    }
    if (!in_cload) continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream row(line);
    long node = 0;
    int dof = 0;
    double value = 0.0;
    if (row >> node >> dof >> value) sum(dof - 1) += value;
  }
  return sum;
}

TEST(CaseExport, LungSmallMeshIsTheReferenceMeshOfSecondOrderWithItsSetsAndForce) {
  const core::Case c = core::load_case(std::string(TISSUE_TEST_CONFIG_DIR) + "/lung_small.json");
  core::GeometryOptions options;
  options.build_node_cloud = false;
  options.fem_mesh_size = 0.027;  // the coarsest level of the mesh study: seconds
  const core::Geometry g = core::build_geometry(c, options);
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / "tissue_test_case_export";
  core::OutputDirectory out(folder);
  const CaseExportSummary s = write_case_export(c, g, out.staging());
  out.commit();

  int fixed = 0, load = 0;
  for (const core::FaceTag tag : g.fem_mesh.face_tags) {
    fixed += tag == core::FaceTag::fixed;
    load += tag == core::FaceTag::load;
  }
  // A straight quadratic tet mesh has a node per vertex and per edge.
  std::set<std::array<int, 2>> edges;
  for (int t = 0; t < g.fem_mesh.num_tets(); ++t)
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j)
        edges.insert({std::min(g.fem_mesh.tets(t, i), g.fem_mesh.tets(t, j)),
                      std::max(g.fem_mesh.tets(t, i), g.fem_mesh.tets(t, j))});

  {
    core::GmshSession session;
    gmsh::open((folder / "mesh.msh").string());
    std::vector<std::size_t> node_tags;
    std::vector<double> coordinates, parametric;
    gmsh::model::mesh::getNodes(node_tags, coordinates, parametric, -1, -1, false, false);
    EXPECT_EQ(node_tags.size(), g.fem_mesh.num_vertices() + edges.size());
    EXPECT_EQ(static_cast<int>(node_tags.size()), s.nodes);
    std::vector<int> types;
    std::vector<std::vector<std::size_t>> element_tags, element_nodes;
    gmsh::model::mesh::getElements(types, element_tags, element_nodes, 3);
    ASSERT_EQ(types, std::vector<int>{kGmshTet10});  // every volume element is a 10-node tet
    EXPECT_EQ(element_tags[0].size(), static_cast<std::size_t>(g.fem_mesh.num_tets()));
    EXPECT_EQ(elements_in_group(3, "TISSUE", kGmshTet10), static_cast<std::size_t>(g.fem_mesh.num_tets()));
    EXPECT_EQ(elements_in_group(2, "SUPPORT", kGmshTriangle6), static_cast<std::size_t>(fixed));
    EXPECT_EQ(elements_in_group(2, "LOAD", kGmshTriangle6), static_cast<std::size_t>(load));
    EXPECT_EQ(elements_in_group(3, "SAMPLE_CELLS", kGmshTet10), static_cast<std::size_t>(s.sample_cells));
    // Straight sides: every midside node of a tet is its edge's midpoint.
    double largest_offset = 0.0;
    const std::vector<std::size_t>& n = element_nodes[0];
    std::map<std::size_t, Eigen::Vector3d> position;
    for (std::size_t i = 0; i < node_tags.size(); ++i)
      position[node_tags[i]] = Eigen::Vector3d(coordinates[3 * i], coordinates[3 * i + 1], coordinates[3 * i + 2]);
    auto x = [&](std::size_t tag) { return position.at(tag); };
    constexpr std::array<std::array<int, 2>, 6> kEdges = {{{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}}};
    for (std::size_t e = 0; e < std::min<std::size_t>(element_tags[0].size(), 200); ++e)
      for (int k = 0; k < 6; ++k)
        largest_offset = std::max(largest_offset, (x(n[10 * e + 4 + k]) - 0.5 * (x(n[10 * e + kEdges[k][0]]) +
                                                                                  x(n[10 * e + kEdges[k][1]])))
                                                      .norm());
    EXPECT_LT(largest_offset, 1e-12);
  }
  nlohmann::json manifest;
  std::ifstream(folder / "export.json") >> manifest;
  EXPECT_EQ(manifest["samples"].size(), static_cast<std::size_t>(g.sample_points.rows()));
  EXPECT_EQ(s.support_faces, fixed);
  EXPECT_EQ(s.load_faces, load);
  // The *CLOAD forces are the case's force (the traction force / area over the patch's area).
  const Eigen::Vector3d sum = cload_sum(folder / "job.inp");
  EXPECT_LT((sum - c.load.force).norm(), 1e-12 * c.load.force.norm()) << sum.transpose();
  // The elastic support's springs carry ∫ k_s dA in total.
  EXPECT_GT(manifest["support"]["stiffness_integral_N_per_m"].get<double>(), 0.0);
  EXPECT_GT(manifest["support"]["pair_springs"].get<int>(), 0);
  std::filesystem::remove_all(folder);
}

}  // namespace
}  // namespace experiments
