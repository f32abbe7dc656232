#pragma once
// The report of generate::classify_on_model (what a mesh made elsewhere was
// classified as on its model), printed and as JSON: shared by the commands
// that take a mesh and its model (`optimize --model`, `curve`).
#include <string>

#include <nlohmann/json.hpp>

#include "curvemesh/generate/classify_on_model.hpp"

namespace cm::cli {

nlohmann::json classification_json(const generate::ModelClassification& c);
std::string render_classification(const generate::ModelClassification& c);

}  // namespace cm::cli
