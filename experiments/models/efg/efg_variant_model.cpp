#include "experiments/models/efg/efg_variant_model.hpp"

#include "experiments/models/efg/meshless_runs.hpp"

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

ModelResult EfgVariantModel::solve(const core::Case& c, const core::Geometry& g, const SolveRequest& request) const {
  core::Case variant_case = c;
  if (variant_ == Variant::paper) variant_case.meshless = c.meshless.in_paper_configuration();
  variant_case.meshless.enrichment = variant_ == Variant::visibility ? "visibility" : "enrichment";
  ModelResult r = solve_meshless(variant_case, g, request.vtu_prefix, [&](const std::string& line) {
    if (request.on_step) request.on_step(name() + ": " + line);
  });
  r.model = "meshless (" + name() + ")";
  return r;
}

}  // namespace experiments
