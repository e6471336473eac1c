#pragma once
// The load case: everything one experiment needs, read from JSON with a strict schema (docs/CONFIG.md).
//
// Units: the JSON states lengths in millimetres, forces in newtons, moduli in pascals, viscosity in
// pascal-seconds and times in seconds. Case stores SI (metres) so both models compute in SI; results
// report displacements in mm, as the paper does.
#include <Eigen/Core>
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/case_error.hpp"
#include "core/kelvin_law.hpp"

namespace core {

struct GeometrySpec {
  enum class Source { builtin_lung, stl };
  Source source = Source::builtin_lung;
  std::string stl_file;           ///< absolute path, resolved against the config's folder
  double stl_unit_to_m = 1e-3;    ///< metres per STL length unit
  double mesh_size = 0.012;       ///< FEM tetrahedron size [m]
  /// Local element sizes as fractions of the mesh size (FEM) and of the node spacing (node cloud), so that a mesh
  /// study refines where the compared quantities live: under the probe (the samples, the traction's edge) and
  /// along the edge of a near_point fixed region (the clamp's edge, where most of the lung's error lives).
  double load_patch_refinement = 0.5;
  double fixed_region_refinement = 0.45;
  /// g >= 1: under the probe the FEM mesh's local size is load_patch_refinement * h * (h / r)^(g - 1), h the mesh size
  /// being meshed and r the load radius (the node cloud keeps load_patch_refinement * its spacing: the grading serves
  /// the reference's mesh study). g = 1 is a fixed fraction of h; g > 1 refines the load patch's edge
  /// (a traction jump, u ~ r log r) faster than the rest as h falls, so that a mesh study reaches the order the
  /// smoothness away from that edge allows (docs/FEM_REFERENCE.md, "Grading the load patch's edge"). Measured
  /// against the load radius, not the case's own mesh size, so that the mesh at a given h is the same whichever
  /// command asks for it (a sweep over /geometry/mesh_size meets the study's levels); at h = r nothing changes.
  double load_patch_grading = 1.0;
  /// Where the load patch's graded size applies (FEM mesh, load_patch_grading > 1):
  ///  * ball: the whole refined ball about the load centre (core/load_patch_zone.hpp), so a mesh study refines the
  ///    samples within it like h^g and those beyond it like h;
  ///  * edge: only a band along the patch's edge (the traction jump), while the ball keeps load_patch_refinement * h,
  ///    so that a mesh study refines every sample at one rate, like h, and its observed order is one number
  ///    (docs/FEM_REFERENCE.md, "One rate at every sample"). Its meshes take their sizes from the size fields
  ///    alone (Gmsh's extension of a curve's size into its faces would spread the edge's size over the patch), so
  ///    they differ from the ball zone's everywhere, at h = r too.
  /// At h = r, where the graded size is load_patch_refinement * h, edge adds no band.
  enum class LoadPatchGradingZone { ball, edge };
  LoadPatchGradingZone load_patch_grading_zone = LoadPatchGradingZone::ball;
  /// The crack's front (the edge of a /cut inside the body: a singular line, u ~ r^(1/2)), FEM mesh only: the local
  /// size along it is crack_front_refinement * h * (h / d)^(g - 1), h the mesh size being meshed, d the cut's depth
  /// and g = crack_front_grading, growing to h over one h. The defaults (1, 1) leave the front at the mesh size,
  /// where the samples converge at order 1; g = 2 makes the front's size fall as h^2 and restores order 2
  /// (docs/FEM_REFERENCE.md, "Grading the crack's front"). Ignored without a cut. The node cloud is not graded.
  double crack_front_refinement = 1.0;
  double crack_front_grading = 1.0;
  /// The local size under the probe when meshing at `size` with a load patch of radius `load_radius` (all three in
  /// one length unit: the mesher passes mm).
  double load_patch_size(double size, double load_radius) const;
  /// The local size along the crack's front when meshing at `size` a cut of depth `cut_depth` (one length unit).
  double crack_front_size(double size, double cut_depth) const;
};

/// Where and how the body is held (docs/CONFIG.md, "/fixed_region"; docs/MATERIAL.md §3).
///
/// Two supports, solved identically by both models:
///  * clamp: u = 0 on the region (a Dirichlet condition in the FEM, the penalty of eq. 23 in the EFG). Its edge is a
///    Dirichlet-free transition where the strain is singular (about r^-1/2), which caps both models' convergence and
///    makes the EFG's answer depend on its penalty factor.
///  * elastic: a Robin condition, traction t = -k_s(x) u over the region (a Winkler foundation standing for the
///    attachment, e.g. the hilum's vessels and bronchi). It is a natural boundary term in both weak forms, so the
///    FEM assembles it as a face integral and the EFG's eq. 23 becomes exactly this term with alpha = k_s(x): both
///    models solve the same problem at every resolution. k_s may fall smoothly to zero over a band inside the region's
///    edge (`taper`), so that the traction has no jump there.
struct FixedRegionSpec {
  enum class Kind { near_point, near_plane };
  enum class Support { clamp, elastic };
  Kind kind = Kind::near_point;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();   ///< [m]
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ(); ///< unit, for near_plane
  double distance = 0.0;                              ///< [m]
  Support support = Support::clamp;
  double stiffness = 0.0;  ///< k_s [Pa/m] of an elastic support, inside the taper band
  double taper = 0.0;      ///< [m] width of the band inside the region's edge over which k_s falls to 0

  /// [m] how far x lies inside the region: distance - |x - point| (near_point) or distance - |(x - point).normal|
  /// (near_plane). Non-negative inside; the region's edge is where it is 0.
  double depth_inside(const Eigen::Vector3d& x) const {
    const double metric = kind == Kind::near_point ? (x - point).norm() : std::abs((x - point).dot(normal));
    return distance - metric;
  }
  /// k_s(x) [Pa/m] of an elastic support: the stated stiffness, times smoothstep(depth / taper) within the taper band
  /// (C1 in x, so the traction -k_s u is continuous across the edge), 0 outside the region. The one definition both
  /// models call.
  double support_stiffness(const Eigen::Vector3d& x) const {
    const double depth = depth_inside(x);
    if (depth <= 0.0) return 0.0;
    if (taper <= 0.0 || depth >= taper) return stiffness;
    const double s = depth / taper;
    return stiffness * s * s * (3.0 - 2.0 * s);
  }
};

/// Traction patch: the surface point nearest `point`, the faces within `radius`, total force ramped.
struct LoadSpec {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< [m]
  double radius = 0.01;                             ///< [m]
  Eigen::Vector3d force = Eigen::Vector3d::Zero();  ///< total force at full load [N]
  double ramp_time = 1.0;                           ///< [s]; force = min(t/ramp_time, 1) * force
  double force_scale(double t) const { return ramp_time <= 0.0 ? 1.0 : std::min(t / ramp_time, 1.0); }
};

struct TimeSpec {
  double total = 1.0;  ///< [s]
  int steps = 10;
  /// Smallest step the models may cut a step back to when Newton fails [s]; 0 selects the default,
  /// dt() / 2^kDefaultCutbackHalvings.
  double min_step = 0.0;
  static constexpr int kDefaultCutbackHalvings = 6;
  double dt() const { return total / steps; }
  double minimum_step() const { return min_step > 0.0 ? min_step : dt() / (1 << kDefaultCutbackHalvings); }
};

/// Sample points (paper §5.4): `count` surface points chosen deterministically near the load point.
struct SampleSpec {
  int count = 10;
  double radius = 0.03;  ///< [m] outermost sample distance from the load centre
};

/// An incision: polyline of surface points swept along `direction` to `depth` (a ruled surface).
struct CutSpec {
  std::vector<Eigen::Vector3d> polyline;  ///< [m]
  double depth = 0.0;                     ///< [m]
  Eigen::Vector3d direction = -Eigen::Vector3d::UnitZ();  ///< unit
  /// Progressive incision (`tissue cut`): the cut advances along its polyline in this many equal increments,
  /// one at the start of each of the first `steps` time steps. Solves that are not progressive cut at once.
  int steps = 1;
};

struct MeshlessSpec {
  /// The named configurations of /meshless/preset. "default" is this project's EFG; "paper" is the paper's own
  /// (§2 and §4 as written): plain Gauss quadrature of eq. 22 (no variationally consistent integration) and the
  /// enrichment of eqs. 29-32 without a front transition. A preset sets the defaults of the keys it names;
  /// the case reader refuses an explicit key that contradicts it (docs/CONFIG.md, docs/MESHLESS.md §1).
  enum class Preset { standard, paper };
  Preset preset = Preset::standard;
  double node_spacing = 0.012;  ///< [m] target spacing of the node cloud
  /// d_max: rho_i = d_max * distance to the k-th nearest node. 1.5 would couple each node to about 0.4x as many
  /// and cut the iterations of the ML-preconditioned Krylov solve about tenfold, but it fails the cantilever's
  /// convergence test (docs/MESHLESS.md §2, "Support size"), so the default stays 2.
  double support_factor = 2.0;
  int support_neighbours = 6;   ///< k
  int quadrature_order = 2;     ///< Gauss order per background tetrahedron
  /// alpha = penalty_factor * K1 / node_spacing (eq. 23) of a clamped fixed region; an elastic support sets alpha =
  /// k_s instead, and the case reader refuses this key with one.
  double penalty_factor = 1e3;
  std::string enrichment = "enrichment";  ///< "enrichment" (eqs. 29–32) or "visibility"
  /// [m] l, over which the enrichment closes the cut at its front (meshless/cut/cut_weights.hpp). The default, 0, is the
  /// paper's function as it stands: the crack opens closest to the FEM's, but the points beside the front carry
  /// large strains, which on the cracked lung with k = 1 left the law's admissible range (configs/lung_large.json
  /// sets l = spacing / 5). docs/MESHLESS.md §5.2 measures each choice.
  double front_transition = 0.012 * kFrontTransitionPerSpacing;
  static constexpr double kFrontTransitionPerSpacing = 0.0;
  /// Linear variationally consistent integration (Chen, Hillman & Rueter 2013; docs/MESHLESS.md §1): a constant per
  /// node added to the test-function gradients so that the background quadrature passes the linear patch test.
  /// false is the paper's plain eq. 22, which fails that test (the "paper" preset).
  bool variationally_consistent = true;

  /// The preset's name as written in a case ("default" or "paper").
  std::string preset_name() const { return preset == Preset::paper ? "paper" : "default"; }
  /// This spec with the paper's configuration in place of this project's choices (the "paper" preset): no
  /// variationally consistent integration and no front transition; every other key (the cloud, the support, the
  /// quadrature order, the cut treatment) is kept. The one place that says what the preset changes.
  MeshlessSpec in_paper_configuration() const {
    MeshlessSpec m = *this;
    m.preset = Preset::paper;
    m.variationally_consistent = false;
    m.front_transition = 0.0;
    return m;
  }
};

struct FemSpec {
  int degree = 2;                   ///< FE_SimplexP degree
  double newton_tolerance = 1e-8;   ///< relative residual
  int max_newton_iterations = 25;
  /// The Newton systems' preconditioner: "amg" (algebraic multigrid, any size and MPI process count) or
  /// "direct" (LU factors, small meshes on one process); docs/FEM_REFERENCE.md.
  std::string linear_solver = "amg";
};

struct OutputSpec {
  bool vtu = true;
  int every = 1;  ///< write VTU every n-th step (the last step is always written)
};

/// The force -> displacement surrogate of paper §3 (eqs. 25-28) that `tissue fit` trains on the meshless node
/// cloud (docs/SURROGATE.md). Every default lives here; read_surrogate() fills the ones that depend on the case.
/// A patch of the surface a haptic probe may touch, covered by trained contacts (docs/SURROGATE.md §4).
struct ContactRegionSpec {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  ///< [m] snapped to the nearest surface node
  double radius = 0.0;        ///< [m] surface nodes within this (straight-line) distance of the centre node
  int training_contacts = 7;  ///< trained contact nodes, spread by farthest-point sampling (>= 3)
  int holdout_contacts = 4;   ///< untrained region nodes solved in full to measure the interpolation
  /// Degree of eq. 28's coefficients as polynomials of the contact position (0, 1 or 2; at most as many
  /// terms, 1/3/6, as training contacts; 2 needs contacts inside the rim too, about 10).
  int position_order = 1;
};

struct SurrogateSpec {
  enum class ResponseTime {
    end_of_ramp,  ///< the first step at which the ramped force is complete (t >= load.ramp_time)
    end,          ///< the last step (time.total): the crept response under the held force
  };
  /// Contact points [m], each snapped to the nearest surface node of the node cloud; absent -> the load point.
  /// With a contact_region, the region's training contacts instead.
  std::vector<Eigen::Vector3d> contact_points;
  std::optional<ContactRegionSpec> contact_region;  ///< a region instead of points (exclusive with them)
  double patch_radius = 0.0;  ///< [m] traction patch around a contact node; absent -> load.radius
  /// The training traction over the patch: uniform on whole faces, or the smooth profile (1 - (r/R)^2)^2, which
  /// a contact region needs (its response is continuous in the contact point). Absent: smooth with a
  /// contact_region, uniform otherwise.
  enum class PatchProfile { uniform, smooth };
  PatchProfile patch_profile = PatchProfile::uniform;
  /// [N] every force component is trained over [-max_force, max_force]: forces up to the paper's 4 N in magnitude.
  double max_force = 4.0;
  int force_levels = 4;       ///< trained levels per sign and axis, evenly spaced up to max_force (0 excluded)
  ResponseTime response_time = ResponseTime::end_of_ramp;
  int max_force_order = 4;       ///< largest lambda tried (eqs. 25-27)
  int max_tangential_order = 6;  ///< largest a tried (eq. 28, surface-local tangential coordinates)
  int max_normal_order = 2;      ///< largest b tried (eq. 28, the normal coordinate)
  int max_contact_order = 2;     ///< largest c tried (eq. 28, the contact terms)
  double contact_length = 0.0;   ///< [m] l of the contact terms; absent -> 2 * patch_radius
  int cv_folds = 5;              ///< k of the k-fold cross-validation that picks lambda, a and b
  int holdout_forces = 2;        ///< full solves at untrained forces, to report the surrogate's error
};

/// Which models `tissue compare`, `reproduce` and `sweep` run on the case (docs/CONFIG.md, /compare). The names are
/// those of experiments/models/model_registry.cpp; core only checks their form, the comparator checks that each is
/// registered (CaseError at /compare/models/i naming the registered ones).
struct CompareSpec {
  std::string reference = "fem";  ///< the model every other is scored against
  /// The scored models, in the order of every table's columns. Default: the proposed model and the baseline of the
  /// paper's Table 1.
  std::vector<std::string> models = {"enrichment", "visibility"};
};

struct Case {
  std::string name;
  std::string description;
  std::string source_file;  ///< the config file it was read from
  nlohmann::json document;  ///< the JSON exactly as read, written next to every result
  GeometrySpec geometry;
  KelvinParameters material;
  FixedRegionSpec fixed_region;
  LoadSpec load;
  TimeSpec time;
  SampleSpec samples;
  std::optional<CutSpec> cut;
  MeshlessSpec meshless;
  FemSpec fem;
  OutputSpec output;
  SurrogateSpec surrogate;  ///< defaults when the case has no /surrogate
  CompareSpec compare;      ///< defaults when the case has no /compare
};

/// Read and validate a case file. Throws CaseError (file, JSON path, what was expected).
Case load_case(const std::string& path);

/// Validate an in-memory document; `file` is used in messages and to resolve relative STL paths.
Case parse_case(const nlohmann::json& document, const std::string& file);

/// Parse JSON text (no comments) and validate it as parse_case does. Throws CaseError, also for invalid JSON.
Case parse_case_text(const std::string& text, const std::string& file);

}  // namespace core
