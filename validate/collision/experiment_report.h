// The collision experiment's report (DESIGN §7): as JSON, with reductions (positive: fewer
// tests), and as text, with changes (negative: fewer tests), both against the first tree.
#pragma once

#include <cstdint>
#include <string>

#include "validate/collision/collision_experiment.h"

namespace vobb::collision {

// What the report names about the run beside its results.
struct ReportHeader {
  std::string mesh;
  int colliders = 0;
  uint64_t seed = 0;
  double collider_scale = 1.0;
};

std::string experiment_report_json(const ReportHeader& header, const ExperimentReport& report);
std::string experiment_report_text(const ReportHeader& header, const ExperimentReport& report);

}  // namespace vobb::collision
