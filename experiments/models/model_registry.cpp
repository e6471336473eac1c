#include "experiments/models/model_registry.hpp"

#include <fmt/format.h>

#include <functional>
#include <utility>

#include "core/case_error.hpp"
#include "experiments/models/efg/efg_variant_model.hpp"
#include "experiments/models/fem/fem_reference_model.hpp"
#include "experiments/models/lrpim/lrpim_case_model.hpp"
#include "experiments/models/zero/zero_model.hpp"

namespace experiments {
namespace {

using Factory = std::function<std::unique_ptr<Model>()>;

/// The registry: one line per model. The order is that of `tissue solve --help` and of the error messages.
const std::vector<Factory>& factories() {
  static const std::vector<Factory> registry{
      [] { return std::make_unique<FemReferenceModel>(); },
      [] { return std::make_unique<EfgVariantModel>(EfgVariantModel::Variant::enrichment); },
      [] { return std::make_unique<EfgVariantModel>(EfgVariantModel::Variant::visibility); },
      [] { return std::make_unique<EfgVariantModel>(EfgVariantModel::Variant::paper); },
      [] { return std::make_unique<LrpimCaseModel>(); },
      [] { return std::make_unique<ZeroModel>(); },
  };
  return registry;
}

}  // namespace

std::vector<std::string> registered_model_names() {
  std::vector<std::string> names;
  for (const auto& make : factories()) names.push_back(make()->name());
  return names;
}

std::unique_ptr<Model> make_model(const std::string& name) {
  for (const auto& make : factories()) {
    std::unique_ptr<Model> m = make();
    if (m->name() == name) return m;
  }
  return nullptr;
}

std::vector<std::unique_ptr<Model>> models_of_case(const core::Case& c) {
  const std::string known = fmt::format("{}", fmt::join(registered_model_names(), ", "));
  std::vector<std::unique_ptr<Model>> models;
  auto add = [&](const std::string& name, const std::string& path) {
    std::unique_ptr<Model> m = make_model(name);
    if (!m)
      throw core::CaseError(c.source_file, path,
                            fmt::format("a registered model ({}), got \"{}\"", known, name));
    models.push_back(std::move(m));
  };
  add(c.compare.reference, "/compare/reference");
  for (std::size_t i = 0; i < c.compare.models.size(); ++i)
    add(c.compare.models[i], fmt::format("/compare/models/{}", i));
  return models;
}

}  // namespace experiments
