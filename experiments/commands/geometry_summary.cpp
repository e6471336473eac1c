#include "experiments/commands/geometry_summary.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <numeric>

namespace experiments {
namespace {

nlohmann::json mesh_summary(const core::TetMesh& m) {
  const int fixed_vertices = std::accumulate(m.vertex_fixed.begin(), m.vertex_fixed.end(), 0);
  int fixed_faces = 0, load_faces = 0;
  for (auto t : m.face_tags) {
    fixed_faces += t == core::FaceTag::fixed;
    load_faces += t == core::FaceTag::load;
  }
  return {{"vertices", m.num_vertices()},
          {"tets", m.num_tets()},
          {"boundary_faces", m.boundary_faces.rows()},
          {"volume_cm3", m.volume() * 1e6},
          {"fixed_vertices", fixed_vertices},
          {"fixed_faces", fixed_faces},
          {"load_faces", load_faces},
          {"load_patch_area_mm2", m.tagged_area(core::FaceTag::load) * 1e6}};
}

}  // namespace

nlohmann::json summarize_geometry(const core::Case& c, const core::Geometry& g) {
  nlohmann::json s;
  s["case"] = c.name;
  s["source"] = c.geometry.source == core::GeometrySpec::Source::builtin_lung ? "builtin_lung"
                                                                              : c.geometry.stl_file;
  s["reference_volume_cm3"] = g.reference_volume * 1e6;
  Eigen::Vector3d lo = g.surface.vertices.colwise().minCoeff(), hi = g.surface.vertices.colwise().maxCoeff();
  s["extent_mm"] = {(hi - lo).x() * 1e3, (hi - lo).y() * 1e3, (hi - lo).z() * 1e3};
  s["fem_mesh"] = mesh_summary(g.fem_mesh);
  s["fem_mesh"]["mesh_size_mm"] = c.geometry.mesh_size * 1e3;
  s["node_cloud"] = mesh_summary(g.meshless_mesh);
  s["node_cloud"]["node_spacing_mm"] = c.meshless.node_spacing * 1e3;
  s["load_centre_mm"] = {g.load_centre.x() * 1e3, g.load_centre.y() * 1e3, g.load_centre.z() * 1e3};
  s["load_force_N"] = {c.load.force.x(), c.load.force.y(), c.load.force.z()};
  nlohmann::json samples = nlohmann::json::array();
  for (Eigen::Index i = 0; i < g.sample_points.rows(); ++i)
    samples.push_back({g.sample_points(i, 0) * 1e3, g.sample_points(i, 1) * 1e3, g.sample_points(i, 2) * 1e3});
  s["sample_points_mm"] = samples;
  if (g.cut) {
    s["cut"] = {{"panels", g.cut->num_panels()},
                {"area_mm2", g.cut->area() * 1e6},
                {"depth_mm", g.cut->depth() * 1e3},
                {"fem_crack_faces", std::count(g.fem_mesh.face_tags.begin(), g.fem_mesh.face_tags.end(), core::FaceTag::crack)},
                {"fem_crack_area_mm2", g.fem_mesh.tagged_area(core::FaceTag::crack) * 1e6}};
  }
  return s;
}

std::string format_geometry_summary(const nlohmann::json& s) {
  std::string out;
  out += fmt::format("case            {}\n", s["case"].get<std::string>());
  out += fmt::format("geometry        {}\n", s["source"].get<std::string>());
  out += fmt::format("extent          {:.1f} x {:.1f} x {:.1f} mm\n", s["extent_mm"][0].get<double>(),
                     s["extent_mm"][1].get<double>(), s["extent_mm"][2].get<double>());
  out += fmt::format("volume          {:.2f} cm^3 (reference surface)\n", s["reference_volume_cm3"].get<double>());
  for (const char* key : {"fem_mesh", "node_cloud"}) {
    const auto& m = s[key];
    out += fmt::format(
        "{:<15} {} {} vertices, {} tets, volume {:.2f} cm^3; fixed: {} vertices / {} faces; load patch: {} faces, "
        "{:.1f} mm^2\n",
        key, key == std::string("fem_mesh") ? "mesh" : "cloud", m["vertices"].get<int>(), m["tets"].get<int>(),
        m["volume_cm3"].get<double>(), m["fixed_vertices"].get<int>(), m["fixed_faces"].get<int>(),
        m["load_faces"].get<int>(), m["load_patch_area_mm2"].get<double>());
  }
  out += fmt::format("load centre     ({:.2f}, {:.2f}, {:.2f}) mm, force ({:.3g}, {:.3g}, {:.3g}) N\n",
                     s["load_centre_mm"][0].get<double>(), s["load_centre_mm"][1].get<double>(),
                     s["load_centre_mm"][2].get<double>(), s["load_force_N"][0].get<double>(),
                     s["load_force_N"][1].get<double>(), s["load_force_N"][2].get<double>());
  out += fmt::format("sample points   {}\n", s["sample_points_mm"].size());
  int i = 0;
  for (const auto& p : s["sample_points_mm"])
    out += fmt::format("  {:>3}  ({:8.2f}, {:8.2f}, {:8.2f}) mm\n", i++, p[0].get<double>(), p[1].get<double>(),
                       p[2].get<double>());
  if (s.contains("cut"))
    out += fmt::format("cut             {} panels, depth {:.1f} mm, area {:.1f} mm^2; FEM crack: {} faces, {:.1f} mm^2 "
                       "(both lips)\n",
                       s["cut"]["panels"].get<int>(), s["cut"]["depth_mm"].get<double>(),
                       s["cut"]["area_mm2"].get<double>(), s["cut"]["fem_crack_faces"].get<int>(),
                       s["cut"]["fem_crack_area_mm2"].get<double>());
  return out;
}

}  // namespace experiments
