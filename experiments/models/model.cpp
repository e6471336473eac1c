#include "experiments/models/model.hpp"

#include <stdexcept>

namespace experiments {

namespace {

/// The series of a model that sets up in each solve: every solve is Model::solve on the prepared geometry.
class SolveEachTime final : public LoadSeries {
 public:
  SolveEachTime(const Model& model, core::Case prepared, const core::Geometry& g)
      : model_(model), prepared_(std::move(prepared)), geometry_(g) {}
  double setup_seconds() const override { return 0.0; }
  ModelResult solve(const core::Case& c, const SolveRequest& request) override {
    check_differs_only_in_force(prepared_, c);
    return model_.solve(c, geometry_, request);
  }

 private:
  const Model& model_;
  core::Case prepared_;
  const core::Geometry& geometry_;
};

}  // namespace

void check_differs_only_in_force(const core::Case& prepared, const core::Case& c) {
  auto without_force = [](nlohmann::json doc) {
    if (doc.is_object() && doc.contains("load") && doc["load"].is_object()) doc["load"].erase("force");
    return doc;
  };
  const nlohmann::json patch = nlohmann::json::diff(without_force(prepared.document), without_force(c.document));
  if (patch.empty()) return;
  throw std::invalid_argument("a load series solves its prepared case under other forces only, but this case differs "
                              "from it at " +
                              patch.front().value("path", std::string("/")) + " (" + c.source_file +
                              "); prepare a new series for it");
}

std::unique_ptr<LoadSeries> Model::prepare_load_series(const core::Case& c, const core::Geometry& g) const {
  return std::make_unique<SolveEachTime>(*this, c, g);
}

}  // namespace experiments
