#include "experiments/export/case_export.hpp"

#include <fmt/format.h>
#include <gmsh.h>

#include <algorithm>
#include <array>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>

#include "core/gmsh_session.hpp"
#include "core/quadratic_mesh_export.hpp"
#include "core/tet_point_location.hpp"
#include "experiments/export/calculix_deck.hpp"
#include "experiments/export/calculix_results.hpp"

namespace experiments {
namespace {

constexpr double kSampleTolerance = 3e-3;  // [m] as reference_fem::FemRunOptions::sample_tolerance
constexpr int kGmshTet10 = 11;

/// The lip of each crack face: the side of the cut (core::RuledSurface::side) of the centroid of the tet it bounds.
std::map<int, int> crack_face_lips(const core::Geometry& g) {
  std::map<std::array<int, 3>, int> crack_faces;  // sorted vertices -> face index
  for (int f = 0; f < g.fem_mesh.boundary_faces.rows(); ++f)
    if (g.fem_mesh.face_tags[static_cast<std::size_t>(f)] == core::FaceTag::crack) {
      std::array<int, 3> key{g.fem_mesh.boundary_faces(f, 0), g.fem_mesh.boundary_faces(f, 1),
                             g.fem_mesh.boundary_faces(f, 2)};
      std::sort(key.begin(), key.end());
      crack_faces[key] = f;
    }
  std::map<int, int> lip;
  if (crack_faces.empty() || !g.cut) return lip;
  const core::TetMesh& m = g.fem_mesh;
  for (int t = 0; t < m.num_tets(); ++t)
    for (int skip = 0; skip < 4; ++skip) {
      std::array<int, 3> key{};
      for (int k = 0, j = 0; k < 4; ++k)
        if (k != skip) key[static_cast<std::size_t>(j++)] = m.tets(t, k);
      std::sort(key.begin(), key.end());
      const auto it = crack_faces.find(key);
      if (it == crack_faces.end()) continue;
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      for (int k = 0; k < 4; ++k) centroid += 0.25 * m.vertices.row(m.tets(t, k)).transpose();
      lip[it->second] = g.cut->side(centroid);
    }
  return lip;
}

std::string readme(const core::Case& c, const CaseExportSummary& s, const CalculixDeck& deck,
                   const core::QuadraticTetMesh& q) {
  const bool elastic = c.fixed_region.support == core::FixedRegionSpec::Support::elastic;
  std::string text = fmt::format(R"(# `tissue export` of case {name}

The FEM reference's problem (the mesh `tissue solve fem` solves, its loads and supports) at its **linear long-time
limit**, for another finite-element program. Written by `tissue export`; docs/FEM_REFERENCE.md, "An independent FE
code: CalculiX", says how it is checked.

## Units

SI throughout: lengths in **m**, forces in N, moduli and tractions in Pa, the support stiffness in Pa/m; CalculiX
answers in m. `tissue import-ccx` writes samples.csv in mm, like every other results folder.

## Files

| file | what |
|---|---|
| `mesh.msh` | Gmsh MSH 4.1: {nodes} nodes, {tets} straight-sided 10-node tets (Gmsh type 11) and the boundary's 6-node triangles, with physical groups |
| `mesh.inp` | the same mesh for Abaqus/CalculiX: `*NODE`, `*ELEMENT, type=C3D10`, `*ELSET` and `*NSET` (node numbers as in mesh.msh) |
| `job.inp` | the CalculiX deck: it includes mesh.inp and adds the material, the support, one linear `*STATIC` step, `*CLOAD` and the output |
| `export.json` | each sample's point, element and local coordinates (read by `tissue import-ccx`), and the figures below |
| `case.json` | the case as read |

## Sets

| name | .msh | .inp | what |
|---|---|---|---|
| `TISSUE` | physical volume | `*ELSET`, `*NSET` | every tet ({tets}); carries the `*SOLID SECTION` |
| `SAMPLE_CELLS` | physical volume | `*ELSET`, `*NSET` | the {sample_cells} tets holding the {samples} samples; the deck prints U on its nodes |
| `SUPPORT` | physical surface | `*NSET` | the fixed region's {support} faces |
| `LOAD` | physical surface | `*NSET` | the load patch's {load} faces |
{crack}| `FREE` | physical surface | — | the other {free} boundary faces |

The .inp holds only the C3D10 elements: CalculiX refuses elements without a section, so the faces are node sets there.

## The problem

- Material: linear isotropic, E = E_inf = K1 K2 / (K1 + K2) = {E} Pa, nu = {nu} (the Kelvin law with k = 0,
  relaxed; the case's k = {k} is not exported).
- Load: the case's force ({fx}, {fy}, {fz}) N as the uniform traction ({tx:.9g}, {ty:.9g}, {tz:.9g}) Pa on the
  {area_mm2:.4f} mm² load patch, as consistent nodal forces (each midside node of a load face a third of its force, the
  corners none) on {load_nodes} nodes; they sum to ({sx:.12g}, {sy:.12g}, {sz:.12g}) N.
- Support: {support_text}

## Running CalculiX and bringing its answer back

In this folder:

```
ccx -i job                     # writes job.dat (U at SAMPLE_CELLS' nodes) and job.frd (U everywhere)
tissue import-ccx . --out ccx_samples     # ccx_samples/samples.csv, the format of every solve's samples.csv
tissue compare {config} --out cmp --external calculix=ccx_samples/samples.csv
```
CalculiX's default solver (SPOOLES) runs on `OMP_NUM_THREADS` threads.
)",
      fmt::arg("name", c.name), fmt::arg("nodes", q.num_nodes()), fmt::arg("tets", q.num_tets()),
      fmt::arg("sample_cells", s.sample_cells), fmt::arg("samples", s.samples), fmt::arg("support", s.support_faces),
      fmt::arg("load", s.load_faces),
      fmt::arg("crack", s.crack_faces > 0
                            ? fmt::format("| `CRACK_LIP_POSITIVE`, `CRACK_LIP_NEGATIVE` | physical surfaces | `*NSET` | "
                                          "the cut's {} faces, on its s > 0 and s < 0 side (core::RuledSurface) |\n",
                                          s.crack_faces)
                            : std::string()),
      fmt::arg("free", s.free_faces), fmt::arg("E", deck.long_time_modulus), fmt::arg("nu", c.material.nu),
      fmt::arg("k", c.material.k), fmt::arg("fx", c.load.force.x()), fmt::arg("fy", c.load.force.y()),
      fmt::arg("fz", c.load.force.z()), fmt::arg("tx", deck.traction.x()), fmt::arg("ty", deck.traction.y()),
      fmt::arg("tz", deck.traction.z()), fmt::arg("area_mm2", deck.load_patch_area * 1e6),
      fmt::arg("load_nodes", deck.load_nodes), fmt::arg("sx", deck.total_load.x()),
      fmt::arg("sy", deck.total_load.y()), fmt::arg("sz", deck.total_load.z()),
      fmt::arg("support_text",
               elastic ? fmt::format("an elastic support t = -k_s(x) u, k_s = {} Pa/m tapered to 0 over {} mm inside "
                                     "the region's edge, as the consistent matrix ∫ k_s N_i N_j dA over the SUPPORT "
                                     "faces in each direction: {} SPRING2 elements (stiffness -K_ij between node "
                                     "pairs) and {} grounded SPRING1 elements (the row sums), exact to round-off; "
                                     "∫ k_s dA = {:.9g} N/m.",
                                     c.fixed_region.stiffness, c.fixed_region.taper * 1e3, deck.pair_springs,
                                     deck.grounded_springs, deck.support_stiffness_integral)
                       : std::string("a clamp, u = 0 on every node of the SUPPORT faces (*BOUNDARY).")),
      fmt::arg("config", c.source_file));
  return text;
}

}  // namespace

CaseExportSummary write_case_export(const core::Case& c, const core::Geometry& g, const std::filesystem::path& folder) {
  const core::TetMesh& mesh = g.fem_mesh;
  if (mesh.num_tets() == 0) throw std::logic_error("write_case_export: the geometry holds no FEM mesh");
  CaseExportSummary summary;
  summary.vertices = mesh.num_vertices();
  summary.tets = mesh.num_tets();
  summary.samples = static_cast<int>(g.sample_points.rows());

  // The samples where the reference evaluates them (reference_fem/sample_evaluator.hpp's rule).
  const std::vector<core::TetPointLocation> located =
      core::locate_points(mesh, g.sample_points, kSampleTolerance, g.cut ? &*g.cut : nullptr);

  core::QuadraticExportSets sets;
  std::map<std::string, std::vector<int>> faces;
  const std::map<int, int> lips = crack_face_lips(g);
  for (int f = 0; f < mesh.boundary_faces.rows(); ++f) {
    switch (mesh.face_tags[static_cast<std::size_t>(f)]) {
      case core::FaceTag::free_surface: faces["FREE"].push_back(f); ++summary.free_faces; break;
      case core::FaceTag::fixed: faces["SUPPORT"].push_back(f); ++summary.support_faces; break;
      case core::FaceTag::load: faces["LOAD"].push_back(f); ++summary.load_faces; break;
      case core::FaceTag::crack:
        faces[lips.count(f) && lips.at(f) < 0 ? "CRACK_LIP_NEGATIVE" : "CRACK_LIP_POSITIVE"].push_back(f);
        ++summary.crack_faces;
        break;
    }
  }
  for (auto& [name, indices] : faces) sets.face_sets.push_back({name, indices});
  std::set<int> sample_cells;
  for (const auto& l : located) sample_cells.insert(l.tet);
  sets.cell_sets.push_back({"SAMPLE_CELLS", std::vector<int>(sample_cells.begin(), sample_cells.end())});
  summary.sample_cells = static_cast<int>(sample_cells.size());

  const core::QuadraticTetMesh quadratic =
      core::write_quadratic_mesh(mesh, sets, folder / "mesh.msh", folder / "mesh.inp");
  summary.nodes = quadratic.num_nodes();
  const CalculixDeck deck = calculix_deck(c, mesh, quadratic, "mesh.inp");
  summary.total_load = deck.total_load;
  summary.springs = deck.pair_springs + deck.grounded_springs;
  write_text_file((folder / "job.inp").string(), deck.text);

  ModelResult cut_description;
  describe_samples_near_cut(g, &cut_description);
  nlohmann::json samples = nlohmann::json::array();
  for (std::size_t i = 0; i < located.size(); ++i) {
    const core::TetPointLocation& l = located[i];
    summary.max_sample_offset = std::max(summary.max_sample_offset, l.offset);
    nlohmann::json s = {{"sample", i},
                        {"point_m", {g.sample_points(static_cast<Eigen::Index>(i), 0),
                                     g.sample_points(static_cast<Eigen::Index>(i), 1),
                                     g.sample_points(static_cast<Eigen::Index>(i), 2)}},
                        {"element", quadratic.tet_elements[static_cast<std::size_t>(l.tet)]},
                        {"local_coordinates", {l.barycentric(1), l.barycentric(2), l.barycentric(3)}},
                        {"offset_m", l.offset}};
    if (!cut_description.sample_cut_distance.empty()) {
      s["cut_distance_m"] = cut_description.sample_cut_distance[i];
      s["lip"] = cut_description.sample_lip[i];
    }
    samples.push_back(s);
  }
  const nlohmann::json manifest = {
      {"format", "tissue export 1"},
      {"case", c.name},
      {"units", {{"length", "m"}, {"force", "N"}, {"stress", "Pa"}}},
      {"problem", "linear long-time limit: k = 0, E = E_inf = K1 K2 / (K1 + K2)"},
      {"mesh", {{"vertices", summary.vertices}, {"nodes", summary.nodes}, {"tets", summary.tets},
                {"degrees_of_freedom", 3 * summary.nodes}, {"support_faces", summary.support_faces},
                {"load_faces", summary.load_faces}, {"crack_faces", summary.crack_faces},
                {"free_faces", summary.free_faces}, {"sample_cells", summary.sample_cells}}},
      {"material", {{"E_inf_Pa", deck.long_time_modulus}, {"nu", c.material.nu}}},
      {"load", {{"force_N", {c.load.force.x(), c.load.force.y(), c.load.force.z()}},
                {"patch_area_m2", deck.load_patch_area},
                {"traction_Pa", {deck.traction.x(), deck.traction.y(), deck.traction.z()}},
                {"cload_sum_N", {deck.total_load.x(), deck.total_load.y(), deck.total_load.z()}},
                {"cload_nodes", deck.load_nodes}}},
      {"support", {{"type", c.fixed_region.support == core::FixedRegionSpec::Support::clamp ? "clamp" : "elastic"},
                   {"pair_springs", deck.pair_springs}, {"grounded_springs", deck.grounded_springs},
                   {"stiffness_integral_N_per_m", deck.support_stiffness_integral}}},
      {"samples", samples}};
  write_text_file((folder / "export.json").string(), manifest.dump(2) + "\n");
  write_text_file((folder / "case.json").string(), c.document.dump(2) + "\n");
  write_text_file((folder / "README.md").string(), readme(c, summary, deck, quadratic));
  return summary;
}

ModelResult calculix_samples(const std::filesystem::path& export_folder, const std::filesystem::path& dat_file) {
  const std::filesystem::path manifest_file = export_folder / "export.json";
  const std::filesystem::path mesh_file = export_folder / "mesh.msh";
  std::ifstream in(manifest_file);
  if (!in)
    throw std::runtime_error(fmt::format("cannot read {}; expected the folder `tissue export CASE --out DIR` wrote",
                                         manifest_file.string()));
  nlohmann::json manifest;
  try {
    manifest = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(fmt::format("{}: not valid JSON ({}); export the case again", manifest_file.string(),
                                         e.what()));
  }
  if (manifest.value("format", std::string()) != "tissue export 1" || !manifest.contains("samples"))
    throw std::runtime_error(fmt::format("{}: not a `tissue export` manifest (format \"tissue export 1\"); export the "
                                         "case again",
                                         manifest_file.string()));
  const CalculixDisplacements u = read_calculix_dat_displacements(dat_file);

  ModelResult result;
  result.model = "calculix";
  const nlohmann::json& samples = manifest["samples"];
  const auto n = static_cast<Eigen::Index>(samples.size());
  result.sample_points.resize(n, 3);
  result.sample_displacements.resize(n, 3);
  bool cut = false;
  for (const auto& s : samples) cut = cut || s.contains("lip");
  if (!std::filesystem::is_regular_file(mesh_file))
    throw std::runtime_error(fmt::format("cannot read {}; expected the mesh `tissue export` wrote beside {}",
                                         mesh_file.string(), manifest_file.string()));
  core::GmshSession session;
  gmsh::open(mesh_file.string());
  for (Eigen::Index i = 0; i < n; ++i) {
    const nlohmann::json& s = samples[static_cast<std::size_t>(i)];
    for (int k = 0; k < 3; ++k) result.sample_points(i, k) = s.at("point_m").at(static_cast<std::size_t>(k)).get<double>();
    const auto element = s.at("element").get<std::size_t>();
    int type = 0;
    std::vector<std::size_t> nodes;
    try {
      gmsh::model::mesh::getElement(element, type, nodes);
    } catch (...) {
      type = 0;
    }
    if (type != kGmshTet10)
      throw std::runtime_error(fmt::format("{}: element {} of sample {} is not a 10-node tet; {} and {} come from "
                                           "different exports, export the case again",
                                           mesh_file.string(), element, i, mesh_file.string(), manifest_file.string()));
    const std::vector<double> local = s.at("local_coordinates").get<std::vector<double>>();
    int components = 0, orientations = 0;
    std::vector<double> shape;
    gmsh::model::mesh::getBasisFunctions(kGmshTet10, local, "Lagrange", components, shape, orientations);
    Eigen::Vector3d value = Eigen::Vector3d::Zero();
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      const auto it = u.by_node.find(nodes[k]);
      if (it == u.by_node.end())
        throw std::runtime_error(fmt::format("{}: node {} (of sample {}'s element {}) is not in its last displacement "
                                             "table; expected U printed on SAMPLE_CELLS or on every node",
                                             dat_file.string(), nodes[k], i, element));
      value += shape[k] * it->second;
    }
    result.sample_displacements.row(i) = value.transpose();
    if (cut) {
      result.sample_cut_distance.push_back(s.value("cut_distance_m", 0.0));
      result.sample_lip.push_back(s.value("lip", 0));
    }
  }
  result.details["source"] = dat_file.string();
  result.details["export"] = export_folder.string();
  result.details["time"] = u.time;
  return result;
}

}  // namespace experiments
