#pragma once
// The models the harness knows by name (experiments/models/model.hpp), and the models a case asks for.
#include <memory>
#include <string>
#include <vector>

#include "core/case.hpp"
#include "experiments/models/model.hpp"

namespace experiments {

/// Every registered model's name, in registration order.
std::vector<std::string> registered_model_names();

/// A new instance of the registered model `name`; nullptr when no model has that name.
std::unique_ptr<Model> make_model(const std::string& name);

/// The case's /compare: the reference first, then the scored models in the case's order. Throws core::CaseError at
/// /compare/reference or /compare/models/i, naming the registered models, when a name is not registered.
std::vector<std::unique_ptr<Model>> models_of_case(const core::Case& c);

}  // namespace experiments
