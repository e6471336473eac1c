#include "experiments/models/efg/efg_variant_model.hpp"

#include <chrono>
#include <memory>

#include "core/load_program.hpp"
#include "experiments/models/efg/meshless_runs.hpp"
#include "meshless/efg/efg_model.hpp"

namespace experiments {

namespace {

/// What each variant says of itself: name, role and one-line description (Model's three texts), in Variant's order.
struct VariantText {
  const char* name;
  const char* role;
  const char* description;
};

const VariantText& text_of(EfgVariantModel::Variant v) {
  static const VariantText table[] = {
      {"enrichment", "proposed: the EFG with MLS weights enriched across the cut (eqs. 29-32)",
       "The paper's EFG model, enrichment across the cut (docs/MESHLESS.md)"},
      {"visibility", "baseline: the EFG with the visibility criterion across the cut",
       "The paper's EFG model, visibility criterion across the cut (the baseline)"},
      {"paper",
       "as published: the proposed EFG in the paper's configuration (plain Gauss quadrature of eq. 22, the "
       "enrichment without a front transition)",
       "The paper's EFG model as published: /meshless/preset \"paper\" (docs/MESHLESS.md §1)"},
  };
  return table[static_cast<int>(v)];
}

}  // namespace

std::string EfgVariantModel::name() const { return text_of(variant_).name; }
std::string EfgVariantModel::role() const { return text_of(variant_).role; }
std::string EfgVariantModel::description() const { return text_of(variant_).description; }

std::string EfgVariantModel::same_as(const core::Case& c) const {
  if (variant_ == Variant::visibility && !c.cut) return "enrichment";
  // A case already in the paper's configuration makes its proposed model the published one.
  if (variant_ == Variant::paper && c.meshless.preset == core::MeshlessSpec::Preset::paper) return "enrichment";
  return {};
}

core::Case EfgVariantModel::variant_case(const core::Case& c) const {
  core::Case v = c;
  if (variant_ == Variant::paper) v.meshless = c.meshless.in_paper_configuration();
  v.meshless.enrichment = variant_ == Variant::visibility ? "visibility" : "enrichment";
  return v;
}

ModelResult EfgVariantModel::solve(const core::Case& c, const core::Geometry& g, const SolveRequest& request) const {
  ModelResult r = solve_meshless(variant_case(c), g, request.vtu_prefix, [&](const std::string& line) {
    if (request.on_step) request.on_step(name() + ": " + line);
  });
  r.model = "meshless (" + name() + ")";
  return r;
}

namespace {

/// EfgVariantModel's series on an uncut body: one meshless::EfgModel, restarted under each force; each run equals a
/// new model's (EfgModel::restart without the factors).
class EfgLoadSeries final : public LoadSeries {
 public:
  EfgLoadSeries(std::string name, core::Case prepared, core::Case variant, const core::Geometry& g)
      : name_(std::move(name)), prepared_(std::move(prepared)), variant_(std::move(variant)), geometry_(g) {
    const auto t0 = std::chrono::steady_clock::now();
    model_ = std::make_unique<meshless::EfgModel>(meshless::problem_from_case(variant_, g));
    set_up_meshless(*model_, variant_);
    setup_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  double setup_seconds() const override { return setup_seconds_; }
  ModelResult solve(const core::Case& c, const SolveRequest& request) override {
    check_differs_only_in_force(prepared_, c);
    MeshlessRun run;
    run.timings_before = model_->timings();
    core::Case variant = variant_;
    variant.load = c.load;
    variant.document = c.document;
    // The traction of the case's force on the prepared patch (core::load_program, as problem_from_case).
    const Eigen::Vector3d traction = core::load_program(variant, model_->problem().mesh).traction;
    // Each force factorises its own tangent, as the LRPIM's series does: the two set up once and solve alike.
    model_->restart({}, [traction](const Eigen::Vector3d&) { return traction; }, /*keep_factors=*/false);
    ModelResult r = run_meshless_steps(*model_, variant, geometry_, request.vtu_prefix,
                                       [&](const std::string& line) {
                                         if (request.on_step) request.on_step(name_ + ": " + line);
                                       },
                                       run);
    r.model = "meshless (" + name_ + ")";
    return r;
  }

 private:
  std::string name_;
  core::Case prepared_, variant_;
  const core::Geometry& geometry_;
  std::unique_ptr<meshless::EfgModel> model_;
  double setup_seconds_ = 0.0;
};

}  // namespace

std::unique_ptr<LoadSeries> EfgVariantModel::prepare_load_series(const core::Case& c, const core::Geometry& g) const {
  if (c.cut) return Model::prepare_load_series(c, g);  // a cut is built into the set-up: set up in each solve
  return std::make_unique<EfgLoadSeries>(name(), c, variant_case(c), g);
}

}  // namespace experiments
