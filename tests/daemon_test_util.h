// Helpers of the tests that run floorposed and its clients as processes: a DDS domain of
// their own, and a simulated walk through the bundled demo plan as a recording.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <string>

#include "core/sim/simulator.h"
#include "platform/floor_plan_io.h"
#include "tools/lib/simulate_recording.h"

namespace floorpose::testing {

// A unique domain per call (and per test process), so parallel ctest runs stay apart.
inline uint32_t UniqueDomain() {
  static int counter = 0;
  return 1 + static_cast<uint32_t>((getpid() * 7 + counter++) % 200);
}

// An office-scenario walk of about length_m through the plan at plan_path, with its wall
// pick and ground truth, written to `recording` (`floorpose simulate --scenario office`).
// Empty on success, else why not.
inline std::string SimulateOfficeWalk(const std::string& plan_path, uint64_t seed, double length_m,
                                      const std::string& recording) {
  const FloorPlanParse plan = platform::LoadFloorPlan(plan_path);
  if (!plan.ok()) return plan.error;
  sim::SimulatorOptions sim;
  sim.seed = seed;
  sim.scenario = sim::Scenario::kOffice;
  sim.target_length_m = length_m;
  tools::SimulateRecordingResult simulated;
  std::string error;
  if (!tools::SimulateToRecording(plan.plan, sim, nullptr, {}, recording, &simulated, &error))
    return error.empty() ? "simulation failed" : error;
  return {};
}

}  // namespace floorpose::testing
