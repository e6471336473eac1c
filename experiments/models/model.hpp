#pragma once
// One model of the comparator: a name, a role, and a solve of a case on the geometry every model shares. The
// comparator (experiments/comparator/compare.hpp), `tissue reproduce`, `tissue sweep` and `tissue solve NAME` see
// models only through this interface and their ModelResult (sample displacements, timings, details), never a model's
// inside. Adding a model is one folder under experiments/models/ and one line in model_registry.cpp
// (docs/ARCHITECTURE.md, "Adding a model").
//
// Lifetime and threads: a Model is a stateless recipe; solve() builds and discards the model's own state, and a
// LoadSeries (prepare_load_series) keeps it across solves of one cloud under several forces. Gmsh and the
// solvers are not thread-safe, so solves run one at a time (as `tissue compare` does).
#include <functional>
#include <memory>
#include <string>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "experiments/models/model_result.hpp"

namespace experiments {

/// What a caller asks of one solve besides the case and the geometry.
struct SolveRequest {
  /// Write the model's own VTU per output step to `vtu_prefix`_NNN.vtu; empty: none.
  std::string vtu_prefix;
  /// One progress line per stage (set-up, each step); may be empty.
  std::function<void(const std::string&)> on_step;
};

/// One model set up once on one case's body and cloud, then solved for loads that differ from that case only in
/// /load/force: the Fig. 9 analogue's measure. A simulator pays its set-up (shape functions, quadrature, pattern)
/// once per cloud, and each new force costs a solve; Model::prepare_load_series makes one. Not thread-safe; the
/// model and the geometry it was prepared from must outlive it.
class LoadSeries {
 public:
  virtual ~LoadSeries() = default;
  /// [s] the set-up done once, by prepare_load_series; 0 when the model sets up in each solve() instead (each result's
  /// own setup_seconds then says what it cost).
  virtual double setup_seconds() const = 0;
  /// Solves `c`, which must be the prepared case but for /load/force (otherwise std::invalid_argument names the first
  /// JSON path that differs). Each solve starts from the undeformed body, as Model::solve does; the result's
  /// setup_seconds is what this solve spent on set-up (0 after a one-off set-up).
  virtual ModelResult solve(const core::Case& c, const SolveRequest& request) = 0;
};

/// Throws std::invalid_argument when `c`'s document differs from `prepared`'s other than at /load/force, naming the
/// first JSON path that does (LoadSeries::solve's precondition). Cases built in code (no document) compare equal.
void check_differs_only_in_force(const core::Case& prepared, const core::Case& c);

class Model {
 public:
  virtual ~Model() = default;

  /// The name in /compare/models, in table columns and in result folders ("fem", "enrichment", ...).
  virtual std::string name() const = 0;
  /// What the model is in a comparison: "reference", "proposed", "baseline", "floor" (a sanity bound every model
  /// must beat) or "external" (another program's samples). A sentence may follow after a colon.
  virtual std::string role() const = 0;
  /// One line for `tissue --help`-style listings and the tables' legends.
  virtual std::string description() const = 0;

  /// Which of the two discretisations of core::Geometry the model reads (the samples are always built).
  virtual bool needs_fem_mesh() const { return false; }
  virtual bool needs_node_cloud() const { return false; }

  /// Why the model cannot solve this case (for example a cut it has no treatment for), or empty when it can. The
  /// comparator reports such a model as "not solved: WHY" instead of failing the comparison.
  virtual std::string cannot_solve(const core::Case& /*c*/) const { return {}; }
  /// The name of another model whose result this one equals, bit for bit, on this case (the visibility variant is
  /// the enrichment variant on a body without a cut), or empty. The comparator then solves once.
  virtual std::string same_as(const core::Case& /*c*/) const { return {}; }
  /// How many times solve() calls SolveRequest::on_step for this case (the progress counter's length).
  virtual int progress_lines(const core::Case& c) const { return 1 + c.time.steps; }

  /// Solve the case on the shared geometry. The result's sample_displacements are at g.sample_points, in metres,
  /// after the last step; set-up and per-step timings are filled where the model has them.
  virtual ModelResult solve(const core::Case& c, const core::Geometry& g, const SolveRequest& request) const = 0;

  /// A series of solves of `c` under other forces on `g` (LoadSeries). The default sets up in each of its solves
  /// (solve() above); a model whose set-up is a large share of a solve sets up here, once.
  virtual std::unique_ptr<LoadSeries> prepare_load_series(const core::Case& c, const core::Geometry& g) const;
};

}  // namespace experiments
