#include "experiments/commands/export_command.hpp"

#include <fmt/format.h>

#include <iostream>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "core/output_directory.hpp"
#include "experiments/export/case_export.hpp"
#include "experiments/models/model_result.hpp"
#include "experiments/io/progress.hpp"

namespace experiments {
namespace {

int run_export(const std::string& config, const std::string& out_dir, double mesh_size_mm) {
  Progress progress("export", 2);
  const core::Case c = core::load_case(config);
  core::OutputDirectory out(out_dir);  // staged: nothing is left behind if anything below fails
  core::GeometryOptions options;
  options.build_node_cloud = false;  // the FEM mesh alone, built exactly as `tissue solve fem` builds it
  if (mesh_size_mm > 0.0) options.fem_mesh_size = mesh_size_mm * 1e-3;
  progress.step("building the geometry and the FEM mesh (Gmsh)");
  const core::Geometry g = core::build_geometry(c, options);
  progress.step("raising the mesh to second order, writing mesh.msh, mesh.inp, job.inp");
  const CaseExportSummary s = write_case_export(c, g, out.staging());
  out.commit();
  progress.done();
  std::cout << fmt::format(
      "{}: {} tets, {} nodes ({} DOFs) of second order; {} support, {} load, {} crack faces; {} samples in {} cells "
      "(farthest {:.3g} mm outside the mesh)\n*CLOAD sum ({:.12g}, {:.12g}, {:.12g}) N; {} support springs\n"
      "wrote {} (units m, N, Pa; README.md says how to run ccx)\n",
      c.name, s.tets, s.nodes, 3 * s.nodes, s.support_faces, s.load_faces, s.crack_faces, s.samples, s.sample_cells,
      s.max_sample_offset * 1e3, s.total_load.x(), s.total_load.y(), s.total_load.z(), s.springs,
      out.destination().string());
  if (c.material.k != 0.0)
    std::cout << fmt::format("note: the deck is the linear long-time limit (k = 0, E = E_inf); the case's k = {} is not "
                             "exported\n",
                             c.material.k);
  return 0;
}

int run_import_ccx(const std::string& export_dir, std::string dat_file, const std::string& out_dir) {
  if (dat_file.empty()) dat_file = (std::filesystem::path(export_dir) / "job.dat").string();
  const ModelResult r = calculix_samples(export_dir, dat_file);
  core::OutputDirectory out(out_dir);
  write_samples_csv(out.file("samples.csv").string(), r);
  out.commit();
  double peak = 0.0;
  for (Eigen::Index i = 0; i < r.sample_displacements.rows(); ++i)
    peak = std::max(peak, r.sample_displacements.row(i).norm());
  std::cout << fmt::format("{} samples from {} (time {}), largest |u| {:.6g} mm\nwrote {}\n",
                           r.sample_displacements.rows(), dat_file, r.details["time"].get<double>(), peak * 1e3,
                           (out.destination() / "samples.csv").string());
  return 0;
}

}  // namespace

void add_export_commands(CLI::App& app) {
  static std::string config, out_dir;
  static double mesh_size_mm = 0.0;
  auto* exp = app.add_subcommand("export", "Write the FEM reference's problem for another FE program (CalculiX)");
  exp->footer(
      "Writes DIR/mesh.msh (Gmsh) and DIR/mesh.inp (Abaqus/CalculiX, C3D10): the mesh `tissue solve fem` solves, "
      "raised to straight-sided 10-node tets, with the sets TISSUE, SAMPLE_CELLS, SUPPORT, LOAD (and the cut's lips); "
      "DIR/job.inp, a CalculiX deck of the linear long-time limit (k = 0, E = E_inf = K1 K2/(K1+K2)): the load as "
      "consistent nodal forces, a clamp as *BOUNDARY or an elastic support as exact springs; DIR/export.json (the "
      "samples' elements) and DIR/README.md. Units: m, N, Pa. Then: cd DIR && ccx -i job && tissue import-ccx . --out "
      "ccx_samples. docs/FEM_REFERENCE.md, \"An independent FE code: CalculiX\".");
  exp->add_option("CASE", config, "Load-case JSON file (schema: docs/CONFIG.md)")->required();
  exp->add_option("--out", out_dir, "Output folder (written atomically)")->required();
  exp->add_option("--mesh-size", mesh_size_mm, "FEM mesh size [mm] instead of the case's /geometry/mesh_size")
      ->check(CLI::Range(0.5, 200.0));
  exp->callback([] { throw CommandResult{run_export(config, out_dir, mesh_size_mm)}; });

  static std::string export_dir, dat_file, import_out;
  auto* imp = app.add_subcommand("import-ccx", "Evaluate a CalculiX result of a `tissue export` at the samples");
  imp->footer(
      "Reads EXPORT_DIR/export.json and EXPORT_DIR/mesh.msh, and the last nodal displacement table of the .dat ccx "
      "wrote (*NODE PRINT U), evaluates each sample with the 10-node tet's shape functions in its element, and writes "
      "OUT/samples.csv in the columns of every solve's samples.csv (mm), for `tissue compare --external`.");
  imp->add_option("EXPORT_DIR", export_dir, "The folder `tissue export` wrote")->required();
  imp->add_option("--dat", dat_file, "CalculiX's .dat file (default: EXPORT_DIR/job.dat)");
  imp->add_option("--out", import_out, "Output folder for samples.csv (written atomically)")->required();
  imp->callback([] { throw CommandResult{run_import_ccx(export_dir, dat_file, import_out)}; });
}

}  // namespace experiments
