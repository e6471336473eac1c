#include "experiments/models/efg/efg_variant_model.hpp"

#include "experiments/models/efg/meshless_runs.hpp"

namespace experiments {

std::string EfgVariantModel::name() const { return variant_ == Variant::enrichment ? "enrichment" : "visibility"; }

std::string EfgVariantModel::role() const {
  return variant_ == Variant::enrichment ? "proposed: the EFG with MLS weights enriched across the cut (eqs. 29-32)"
                                         : "baseline: the EFG with the visibility criterion across the cut";
}

std::string EfgVariantModel::description() const {
  return variant_ == Variant::enrichment ? "The paper's EFG model, enrichment across the cut (docs/MESHLESS.md)"
                                         : "The paper's EFG model, visibility criterion across the cut (the baseline)";
}

std::string EfgVariantModel::same_as(const core::Case& c) const {
  return variant_ == Variant::visibility && !c.cut ? "enrichment" : std::string();
}

ModelResult EfgVariantModel::solve(const core::Case& c, const core::Geometry& g, const SolveRequest& request) const {
  core::Case variant_case = c;
  variant_case.meshless.enrichment = name();
  ModelResult r = solve_meshless(variant_case, g, request.vtu_prefix, [&](const std::string& line) {
    if (request.on_step) request.on_step(name() + ": " + line);
  });
  r.model = "meshless (" + name() + ")";
  return r;
}

}  // namespace experiments
