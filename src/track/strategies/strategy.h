// A simulation strategy (paper: "Multiple Simulations and Error"): one way of running
// the physics fit for the current frame, starting from the previous frame's best
// state. Strategies only bias the simulation (welds, cones, drives, labelled points)
// and must leave the world's configuration as they found it; the shared Simulator and
// the error metric do the rest. To add one: a file here, a StrategyKind, and a line in
// makeStrategy().
#pragma once

#include <memory>

#include "dynahand/tracker.h"
#include "track/finger_detector.h"
#include "track/simulation.h"

namespace dynahand::track {

struct StrategyContext {
  HandRig& rig;
  Simulator& simulator;
  const FrameInput& input;  // points, planes, free space of this hand
  int substeps = 3;
  double sequenceTime = 0.0;                        // s, for strategies that cycle over time
  float flipPeriod = 0.5f;                          // s
  const FingerDetection* detection = nullptr;       // this frame's five-finger detection
  const model::JointAngles* startAngles = nullptr;  // the model angles at the frame start
};

class Strategy {
 public:
  virtual ~Strategy() = default;
  virtual StrategyKind kind() const = 0;
  // Runs the simulation; false when it had nothing to do (no candidate this frame).
  virtual bool run(StrategyContext& context) = 0;
};

std::unique_ptr<Strategy> makeStrategy(StrategyKind kind);

}  // namespace dynahand::track
