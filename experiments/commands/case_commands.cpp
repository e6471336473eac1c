#include "experiments/commands/case_commands.hpp"

#include <fmt/format.h>

#include <iostream>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "core/output_directory.hpp"
#include "experiments/commands/geometry_summary.hpp"
#include "experiments/models/model_result.hpp"
#include "experiments/io/progress.hpp"
#include "experiments/io/vtu_writer.hpp"

namespace experiments {
namespace {

Eigen::MatrixXd column(const std::vector<char>& flags) {
  Eigen::MatrixXd m(static_cast<Eigen::Index>(flags.size()), 1);
  for (std::size_t i = 0; i < flags.size(); ++i) m(static_cast<Eigen::Index>(i), 0) = flags[i];
  return m;
}

Eigen::MatrixXd face_tags(const core::TetMesh& mesh) {
  Eigen::MatrixXd m(static_cast<Eigen::Index>(mesh.face_tags.size()), 1);
  for (std::size_t i = 0; i < mesh.face_tags.size(); ++i)
    m(static_cast<Eigen::Index>(i), 0) = static_cast<int>(mesh.face_tags[i]);
  return m;
}

void write_mesh_files(const core::OutputDirectory& out, const std::string& prefix, const core::TetMesh& mesh) {
  write_tet_vtu(out.file(prefix + "_tets.vtu").string(), mesh.vertices, mesh.tets,
                {{"fixed", column(mesh.vertex_fixed)}}, {});
  write_triangle_vtu(out.file(prefix + "_boundary.vtu").string(), mesh.vertices, mesh.boundary_faces, {},
                     {{"region", face_tags(mesh)}});
}

int run_check(const std::string& config) {
  Progress progress("case check", 2);
  const core::Case c = core::load_case(config);
  progress.step("building geometry and meshes (Gmsh)");
  const core::Geometry g = core::build_geometry(c);
  progress.done();
  std::cout << format_geometry_summary(summarize_geometry(c, g));
  return 0;
}

int run_mesh(const std::string& config, const std::string& out_dir) {
  Progress progress("case mesh", 3);
  const core::Case c = core::load_case(config);
  core::OutputDirectory out(out_dir);  // staged: nothing is left behind if anything below fails
  progress.step("building geometry and meshes (Gmsh)");
  const core::Geometry g = core::build_geometry(c);
  progress.step("writing VTU files");
  write_mesh_files(out, "fem_mesh", g.fem_mesh);
  write_mesh_files(out, "meshless_cells", g.meshless_mesh);
  write_point_vtu(out.file("meshless_nodes.vtu").string(), g.meshless_mesh.vertices,
                  {{"fixed", column(g.meshless_mesh.vertex_fixed)}});
  Eigen::MatrixXd index(g.sample_points.rows(), 1);
  for (Eigen::Index i = 0; i < index.rows(); ++i) index(i, 0) = static_cast<double>(i);
  write_point_vtu(out.file("sample_points.vtu").string(), g.sample_points, {{"sample", index}});
  if (g.cut) {
    core::PointMatrix v;
    core::TriMatrix t;
    g.cut->triangulate(&v, &t);
    write_triangle_vtu(out.file("cut_surface.vtu").string(), v, t, {}, {});
  }
  const nlohmann::json summary = summarize_geometry(c, g);
  write_text_file(out.file("case.json").string(), c.document.dump(2) + "\n");
  write_text_file(out.file("geometry.json").string(), summary.dump(2) + "\n");
  out.commit();
  progress.done();
  std::cout << format_geometry_summary(summary);
  std::cout << fmt::format("wrote VTU files to {}\n", out.destination().string());
  return 0;
}

}  // namespace

void add_case_commands(CLI::App& app) {
  auto* group = app.add_subcommand("case", "Validate a load case and inspect its geometry");
  group->require_subcommand(1);

  auto* check = group->add_subcommand("check", "Validate CONFIG and print its geometry summary");
  check->footer("The summary: volume, node and tet counts, fixed nodes, the load patch and the sample points.");
  static std::string check_config;
  check->add_option("CONFIG", check_config, "Load-case JSON file (schema: docs/CONFIG.md)")->required();
  check->callback([] { throw CommandResult{run_check(check_config)}; });

  auto* mesh = group->add_subcommand("mesh", "Write VTU files of both meshes, the samples and the cut");
  mesh->footer("The FEM mesh, the node cloud and its integration cells, the samples and the cut, with region tags.");
  static std::string mesh_config, mesh_out;
  mesh->add_option("CONFIG", mesh_config, "Load-case JSON file")->required();
  mesh->add_option("--out", mesh_out, "Output folder (written atomically)")->required();
  mesh->callback([] { throw CommandResult{run_mesh(mesh_config, mesh_out)}; });
}

}  // namespace experiments
