#pragma once
// The FEM reference's remaining discretisation error at the samples, from a mesh study's last three levels
// (tissue verify fem; the comparator's error bar, experiments/comparator/compare_metrics.hpp).
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/case.hpp"

namespace experiments {

/// How far an observed order may sit from the expected one and still count as asymptotic.
constexpr double kOrderTolerance = 0.3;
/// The lowest order the samples converge at here (a clamp's edge or a crack's front): an estimate outside the
/// asymptotic range never assumes less, since order 0.2 would give 28 % from a 1 % change.
constexpr double kLowestOrder = 1.0;

/// The order at which a case's sample displacements converge under the study's refinement (docs/EXPERIMENTS.md,
/// "The reference's error bar", "Which order is expected"). The samples lie away from the solution's rough lines, so
/// each line holds them to about the square of its energy error, (h_line)^(2 lambda) for a singularity r^lambda
/// whose local size h_line falls like h^g. The smallest of:
///  * degree + 1 (P2: 3), the element's own pointwise order where the solution is smooth, the samples' local size
///    being proportional to h;
///  * 2: the meshes are straight-sided tetrahedra (an affine mapping, reference_fem/viscoelastic_solver.cpp), so a
///    curved surface is faceted, O(h^2) from the true one, and P2 on such a domain converges like h^2 in
///    displacement, not h^3 (Strang & Berger 1971; Ciarlet, The Finite Element Method for Elliptic Problems,
///    §4.4). This is what sets the lung's expected order wherever its other lines are graded;
///  * a clamp's edge, r^(1/2), refined in proportion to h: 1;
///  * a crack's front, r^(1/2), graded like h^g (/geometry/refinement/crack_front_grading): g.
/// Two lines give 2 or more and so never lower it: an elastic support's edge without a taper (k_s jumps, u ~ r log r,
/// refined like h: 2) and the load patch's edge (a traction jump, u ~ r log r, graded like h^g: 2g). Ungraded, the
/// patch's edge lies within an element or two of the samples at practical sizes, so they see its local error and
/// converge at about 1 (1.13 / 1.04 observed on the lung); the estimate then takes the observed order, which gives
/// the larger bar.
double expected_sample_order(const core::Case& c);

struct MeshStudyEstimate {
  /// Always (with three levels or more and the last two different): expected_order, estimated_error_of_finest_relative,
  /// kind ("richardson" or "assumed_order"), observed_orders (one per consecutive three levels). Richardson
  /// (observed order within kOrderTolerance of the expected one): observed_order. Otherwise: assumed_order (see
  /// estimate_remaining_error), observed_order_not_used when one was found, and a note saying that the figure is an estimate
  /// outside the asymptotic range, not a bound. {note} alone when the last two levels agree exactly; empty with
  /// fewer than three levels.
  nlohmann::json json;
  std::string sentence;  ///< the same for fem.md
  /// The samples extrapolated from the last two levels with the order the estimate used,
  /// u_f + (u_f - u_{f-1}) / (r^p - 1), in the units and shape of `u`; empty when there is no estimate.
  Eigen::MatrixXd extrapolated;
};

/// `u[l]`: every sample displacement of level l (any shape, same for all levels), `h_mm[l]` its mesh size,
/// coarse to fine. The error is relative to the finest level's norm. An observed order within kOrderTolerance of
/// `expected_order` is extrapolated with. Any other is not in the asymptotic range (or, on non-nested meshes, is
/// blurred by their mesh-to-mesh noise; docs/FEM_REFERENCE.md), and the estimate assumes the
/// order that gives the larger bar: below the expected order the observed one (not less than kLowestOrder: a coarse
/// level not yet asymptotic, or samples within an element of a singular line, which converge at about order 1
/// before the mesh resolves them), above it the expected one (a larger order would shrink the bar on the strength
/// of a coincidence). It says so, and that the figure is an estimate, not a bound.
MeshStudyEstimate estimate_remaining_error(const std::vector<Eigen::MatrixXd>& u, const std::vector<double>& h_mm,
                                           double expected_order);

/// What fem.md adds after the estimate's sentence when a study of one mesh per level is outside the asymptotic range
/// (`estimate.json["kind"]` "assumed_order"): that the order may be the noise's, and how to average it out; empty
/// otherwise. Gmsh's levels are not nested, and on the one-rate lung_small the noise between meshes 1 % apart is 40–50 %
/// of the changes between levels: the 27 choices of one of three meshes at each of 8 / 5.3 / 3.55 mm give orders from
/// 1.22 to 2.69, the means of the three 1.88 (docs/FEM_REFERENCE.md, "The linear lab").
std::string one_mesh_per_level_hint(const MeshStudyEstimate& estimate, int meshes_per_level);

/// The observed order of each consecutive three levels over the rows `rows` of every `u[l]` (one row per sample, as
/// `estimate_remaining_error` takes them; 0 where the differences do not decrease), so that groups of samples
/// refined at different rates can be judged apart: a study that grades the load patch refines the samples within
/// core::kLoadPatchBallRadii of the load centre like h^g and those beyond like h, and one order over all of them
/// mixes the two (docs/EXPERIMENTS.md, "Why no single order settles"). Empty with fewer than three levels.
std::vector<double> observed_orders(const std::vector<Eigen::MatrixXd>& u, const std::vector<double>& h_mm,
                                    const std::vector<Eigen::Index>& rows);

}  // namespace experiments
