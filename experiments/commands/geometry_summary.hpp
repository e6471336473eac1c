#pragma once
// A human- and machine-readable summary of a case's geometry (what `tissue case check` prints).
#include <nlohmann/json.hpp>
#include <string>

#include "core/case.hpp"
#include "core/geometry.hpp"

namespace experiments {

nlohmann::json summarize_geometry(const core::Case& c, const core::Geometry& g);
std::string format_geometry_summary(const nlohmann::json& summary);

}  // namespace experiments
