#include "core/case.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/json_reader.hpp"

namespace core {
namespace {

constexpr double kMm = 1e-3;  // the schema's length unit

double unit_to_metres(const JsonReader& r, const std::string& key) {
  const std::string u = r.choice(key, {"mm", "cm", "m"}, std::string("mm"));
  if (u == "mm") return 1e-3;
  if (u == "cm") return 1e-2;
  return 1.0;
}

GeometrySpec read_geometry(const JsonReader& r) {
  GeometrySpec g;
  const std::string source = r.choice("source", {"builtin_lung", "stl"});
  if (source == "stl") {
    g.source = GeometrySpec::Source::stl;
    std::filesystem::path p = r.string("stl_file");
    if (p.is_relative()) p = std::filesystem::path(r.file()).parent_path() / p;
    g.stl_file = p.lexically_normal().string();
    if (!std::filesystem::exists(g.stl_file))
      r.fail("stl_file", fmt::format("expected an existing STL file, but \"{}\" does not exist", g.stl_file));
    g.stl_unit_to_m = unit_to_metres(r, "length_unit");
  }
  g.mesh_size = r.in_range("mesh_size", 0.5, 200.0, true, true) * kMm;
  if (auto refinement = r.optional_object("refinement")) {
    g.load_patch_refinement = refinement->in_range("load_patch", 0.05, 1.0, true, true, g.load_patch_refinement);
    g.fixed_region_refinement =
        refinement->in_range("fixed_region", 0.05, 1.0, true, true, g.fixed_region_refinement);
    g.load_patch_grading = refinement->in_range("load_patch_grading", 1.0, 3.0, true, true, g.load_patch_grading);
    if (refinement->choice("load_patch_grading_zone", {"ball", "edge"}, "ball") == "edge")
      g.load_patch_grading_zone = GeometrySpec::LoadPatchGradingZone::edge;
    g.crack_front_refinement =
        refinement->in_range("crack_front", 0.05, 1.0, true, true, g.crack_front_refinement);
    g.crack_front_grading = refinement->in_range("crack_front_grading", 1.0, 3.0, true, true, g.crack_front_grading);
    refinement->finish();
  }
  r.finish();
  return g;
}

KelvinParameters read_material(const JsonReader& r) {
  KelvinParameters m;
  m.K1 = r.positive("K1");
  m.K2 = r.positive("K2");
  m.eta = r.positive("eta");
  m.nu = r.in_range("nu", -1.0, 0.5, false, false);
  m.k = r.in_range("k", -1e3, 1e3, true, true, 0.0);
  m.slope_floor = r.in_range("slope_floor", 0.0, 1.0, true, false, 0.0);  // docs/MATERIAL.md §1.7
  r.finish();
  return m;
}

FixedRegionSpec read_fixed_region(const JsonReader& r) {
  FixedRegionSpec f;
  const std::string kind = r.choice("type", {"near_point", "near_plane"});
  f.kind = kind == "near_point" ? FixedRegionSpec::Kind::near_point : FixedRegionSpec::Kind::near_plane;
  f.point = r.vector3("point") * kMm;
  if (f.kind == FixedRegionSpec::Kind::near_plane) {
    const Eigen::Vector3d n = r.vector3("normal");
    if (n.norm() < 1e-12) r.fail("normal", "expected a non-zero normal vector");
    f.normal = n.normalized();
  }
  f.distance = r.positive("distance") * kMm;
  f.support = r.choice("support", {"clamp", "elastic"}, std::string("clamp")) == "elastic"
                  ? FixedRegionSpec::Support::elastic
                  : FixedRegionSpec::Support::clamp;
  if (f.support == FixedRegionSpec::Support::elastic) {
    f.stiffness = r.in_range("stiffness", 0.0, 1e15, false, true);  // Pa/m, as stated
    f.taper = r.in_range("taper", 0.0, f.distance / kMm, true, true, 0.0) * kMm;
  } else {
    for (const char* key : {"stiffness", "taper"})
      if (r.has(key))
        r.fail(key, "applies only to an elastic support; expected \"support\": \"elastic\" beside it, or no such "
                    "key for a clamp");
  }
  r.finish();
  return f;
}

LoadSpec read_load(const JsonReader& r) {
  LoadSpec l;
  l.point = r.vector3("point") * kMm;
  l.radius = r.positive("radius") * kMm;
  l.force = r.vector3("force");
  if (l.force.norm() == 0.0) r.fail("force", "expected a non-zero force vector [N]");
  l.ramp_time = r.in_range("ramp_time", 0.0, INFINITY, true, false, 1.0);
  r.finish();
  return l;
}

TimeSpec read_time(const JsonReader& r) {
  TimeSpec t;
  t.total = r.positive("total");
  t.steps = r.integer("steps", 1, 100000);
  // Absent: 0, which TimeSpec::minimum_step() turns into its default.
  t.min_step = r.in_range("min_step", 0.0, t.dt(), false, true, 0.0);
  r.finish();
  return t;
}

SampleSpec read_samples(const JsonReader& r) {
  SampleSpec s;
  s.count = r.integer("count", 1, 1000, 10);
  s.radius = r.positive("radius", 30.0) * kMm;
  r.finish();
  return s;
}

CutSpec read_cut(const JsonReader& r) {
  CutSpec c;
  c.polyline = r.vector3_list("polyline", 2);
  for (auto& p : c.polyline) p *= kMm;
  for (std::size_t i = 1; i < c.polyline.size(); ++i)
    if ((c.polyline[i] - c.polyline[i - 1]).norm() < 1e-6)
      r.fail("polyline", fmt::format("expected distinct consecutive points, but points {} and {} coincide",
                                     i - 1, i));
  c.depth = r.positive("depth") * kMm;
  const Eigen::Vector3d d = r.vector3("direction");
  if (d.norm() < 1e-12) r.fail("direction", "expected a non-zero depth direction");
  c.direction = d.normalized();
  c.steps = r.integer("steps", 1, 100000, 1);
  r.finish();
  return c;
}

MeshlessSpec read_meshless(const std::optional<JsonReader>& r, double fem_mesh_size, const FixedRegionSpec& fixed) {
  MeshlessSpec m;
  m.node_spacing = fem_mesh_size;
  m.front_transition = fem_mesh_size * MeshlessSpec::kFrontTransitionPerSpacing;
  if (!r) return m;
  m.node_spacing = r->in_range("node_spacing", 0.5, 200.0, true, true, fem_mesh_size / kMm) * kMm;
  const MeshlessSpec defaults;  // the defaults are stated once, in core/case.hpp
  m.support_factor = r->in_range("support_factor", 1.0, 10.0, true, true, defaults.support_factor);
  m.support_neighbours = r->integer("support_neighbours", 4, 100, defaults.support_neighbours);
  m.quadrature_order = r->integer("quadrature_order", 1, 8, defaults.quadrature_order);
  // The penalty of eq. 23 approximates a clamp; an elastic support is the same term with alpha = k_s, exactly.
  if (fixed.support == FixedRegionSpec::Support::elastic && r->has("penalty_factor"))
    r->fail("penalty_factor", "applies only to a clamped fixed region; with /fixed_region/support \"elastic\" the "
                              "EFG imposes the support exactly (alpha = /fixed_region/stiffness), so expected no "
                              "penalty_factor here");
  m.penalty_factor = r->in_range("penalty_factor", 1.0, 1e12, true, true, defaults.penalty_factor);
  m.enrichment = r->choice("enrichment", {"enrichment", "visibility"}, defaults.enrichment);
  m.front_transition = r->in_range("front_transition", 0.0, 200.0, true, true,
                                   m.node_spacing * MeshlessSpec::kFrontTransitionPerSpacing / kMm) *
                       kMm;
  m.variationally_consistent = r->boolean("variationally_consistent", defaults.variationally_consistent);
  if (r->choice("preset", {"default", "paper"}, "default") == "paper") {
    const MeshlessSpec paper = m.in_paper_configuration();
    // The preset names the paper's model; a key that says otherwise would give a model that is neither.
    if (r->has("variationally_consistent") && m.variationally_consistent != paper.variationally_consistent)
      r->fail("variationally_consistent",
              "expected false or no key: /meshless/preset \"paper\" is the paper's plain Gauss quadrature of eq. 22, "
              "without variationally consistent integration");
    if (r->has("front_transition") && m.front_transition != paper.front_transition)
      r->fail("front_transition", "expected 0 or no key: /meshless/preset \"paper\" is the paper's enrichment "
                                  "(eqs. 29-32) without a front transition");
    m = paper;
  }
  r->finish();
  return m;
}

FemSpec read_fem(const std::optional<JsonReader>& r) {
  FemSpec f;
  if (!r) return f;
  f.degree = r->integer("degree", 1, 2, f.degree);  // f holds the defaults of core/case.hpp
  f.newton_tolerance = r->in_range("newton_tolerance", 0.0, 1e-2, false, true, f.newton_tolerance);
  f.max_newton_iterations = r->integer("max_newton_iterations", 1, 200, f.max_newton_iterations);
  f.linear_solver = r->choice("linear_solver", {"amg", "direct"}, f.linear_solver);
  r->finish();
  return f;
}

OutputSpec read_output(const std::optional<JsonReader>& r) {
  OutputSpec o;
  if (!r) return o;
  o.vtu = r->boolean("vtu", o.vtu);  // o holds the defaults of core/case.hpp
  o.every = r->integer("every", 1, 1000000, o.every);
  r->finish();
  return o;
}

CompareSpec read_compare(const std::optional<JsonReader>& r) {
  CompareSpec spec;
  if (!r) return spec;
  spec.reference = r->string("reference", spec.reference);
  if (r->has("models")) {
    const nlohmann::json& list = r->array("models", 1, "a non-empty array of model names, e.g. [\"enrichment\", "
                                                       "\"visibility\"]");
    spec.models.clear();
    for (std::size_t i = 0; i < list.size(); ++i) {
      const std::string at = fmt::format("models/{}", i);
      if (!list[i].is_string() || list[i].get<std::string>().empty())
        r->fail(at, "a model name (a non-empty string), got " + describe_json(list[i]));
      const std::string name = list[i].get<std::string>();
      if (name == spec.reference)
        r->fail(at, fmt::format("a model other than the reference \"{}\" (it is scored against itself)", name));
      if (std::find(spec.models.begin(), spec.models.end(), name) != spec.models.end())
        r->fail(at, fmt::format("each model once (\"{}\" is listed twice)", name));
      spec.models.push_back(name);
    }
  }
  r->finish();
  return spec;
}

SurrogateSpec read_surrogate(const std::optional<JsonReader>& r, const LoadSpec& load) {
  SurrogateSpec s;
  s.contact_points = {load.point};
  s.patch_radius = load.radius;
  s.contact_length = 2.0 * s.patch_radius;
  if (!r) return s;
  if (r->has("contact_points")) {
    s.contact_points = r->vector3_list("contact_points", 1);
    for (auto& p : s.contact_points) p *= kMm;
  }
  if (auto region = r->optional_object("contact_region")) {
    if (r->has("contact_points"))
      r->fail("contact_region", "either contact_points or a contact_region, not both (the region chooses its own "
                                "training contacts)");
    ContactRegionSpec g;
    g.centre = region->vector3("centre") * kMm;
    g.radius = region->positive("radius") * kMm;
    g.training_contacts = region->integer("training_contacts", 3, 64, g.training_contacts);
    g.holdout_contacts = region->integer("holdout_contacts", 0, 64, g.holdout_contacts);
    g.position_order = region->integer("position_order", 0, 2, g.position_order);
    if ((g.position_order + 1) * (g.position_order + 2) / 2 > g.training_contacts)
      region->fail("position_order",
                   fmt::format("expected a degree that {} training contacts determine (a degree-{} polynomial of the "
                               "position has {} terms); lower position_order or raise training_contacts",
                               g.training_contacts, g.position_order,
                               (g.position_order + 1) * (g.position_order + 2) / 2));
    region->finish();
    s.contact_points = {g.centre};
    s.contact_region = g;
  }
  s.patch_radius = r->positive("patch_radius", load.radius / kMm) * kMm;
  s.patch_profile = r->choice("patch_profile", {"uniform", "smooth"},
                              std::string(s.contact_region ? "smooth" : "uniform")) == "smooth"
                        ? SurrogateSpec::PatchProfile::smooth
                        : SurrogateSpec::PatchProfile::uniform;
  s.max_force = r->in_range("max_force", 0.0, 1e4, false, true, s.max_force);
  s.force_levels = r->integer("force_levels", 2, 50, s.force_levels);
  s.response_time = r->choice("response_time", {"end_of_ramp", "end"}, std::string("end_of_ramp")) == "end"
                        ? SurrogateSpec::ResponseTime::end
                        : SurrogateSpec::ResponseTime::end_of_ramp;
  s.max_force_order = r->integer("max_force_order", 1, 8, s.max_force_order);
  if (s.max_force_order > 2 * s.force_levels - 1)
    r->fail("max_force_order", fmt::format("expected at most 2 * force_levels - 1 = {} (fewer coefficients than "
                                           "trained levels), got {}",
                                           2 * s.force_levels - 1, s.max_force_order));
  s.max_tangential_order = r->integer("max_tangential_order", 0, 12, s.max_tangential_order);
  s.max_normal_order = r->integer("max_normal_order", 0, 8, s.max_normal_order);
  s.max_contact_order = r->integer("max_contact_order", 0, 6, s.max_contact_order);
  s.contact_length = r->positive("contact_length", 2.0 * s.patch_radius / kMm) * kMm;
  s.cv_folds = r->integer("cv_folds", 2, 20, s.cv_folds);
  s.holdout_forces = r->integer("holdout_forces", 0, 100, s.holdout_forces);
  r->finish();
  return s;
}

}  // namespace

namespace {

/// A local size graded against a fixed length L of the problem: f * h * (h / L)^(g - 1). It falls like h^g under
/// refinement, and equals f * h at h = L (so grading changes nothing at the size where it is anchored).
double graded_size(double refinement, double grading, double size, double anchor) {
  return refinement * size * std::pow(size / anchor, grading - 1.0);
}

}  // namespace

double GeometrySpec::load_patch_size(double size, double load_radius) const {
  return graded_size(load_patch_refinement, load_patch_grading, size, load_radius);
}

double GeometrySpec::crack_front_size(double size, double cut_depth) const {
  return graded_size(crack_front_refinement, crack_front_grading, size, cut_depth);
}

Case parse_case(const nlohmann::json& document, const std::string& file) {
  JsonReader root(file, document, "");
  Case c;
  c.source_file = file;
  c.document = document;
  c.name = root.string("name");
  if (c.name.empty()) root.fail("name", "expected a non-empty case name");
  c.description = root.string("description", std::string());
  c.geometry = read_geometry(root.object("geometry"));
  c.material = read_material(root.object("material"));
  c.fixed_region = read_fixed_region(root.object("fixed_region"));
  c.load = read_load(root.object("load"));
  c.time = read_time(root.object("time"));
  if (auto s = root.optional_object("samples")) c.samples = read_samples(*s);
  if (auto cut = root.optional_object("cut")) c.cut = read_cut(*cut);
  c.meshless = read_meshless(root.optional_object("meshless"), c.geometry.mesh_size, c.fixed_region);
  c.fem = read_fem(root.optional_object("fem"));
  c.output = read_output(root.optional_object("output"));
  c.surrogate = read_surrogate(root.optional_object("surrogate"), c.load);
  c.compare = read_compare(root.optional_object("compare"));
  root.finish();
  return c;
}

Case parse_case_text(const std::string& text, const std::string& file) {
  nlohmann::json document;
  try {
    document = nlohmann::json::parse(text, nullptr, true, /*ignore_comments=*/false);
  } catch (const nlohmann::json::exception& e) {
    // parse_error, and out_of_range for a number beyond double (e.g. 1e999)
    throw CaseError(file, "", fmt::format("expected valid JSON: {}", e.what()));
  }
  return parse_case(document, file);
}

Case load_case(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw CaseError(path, "", "cannot open the case file (does it exist and is it readable?)");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_case_text(text.str(), path);
}

}  // namespace core
