// A simulation strategy (paper: "Multiple Simulations and Error"): one way of running
// the physics fit for the current frame, starting from the previous frame's best
// state. Strategies only bias the simulation (welds, cones, drives, labelled points)
// and must leave the world's configuration as they found it; the shared Simulator and
// the error metric do the rest. A strategy says what each physics step of its run is
// (beforeStep), and the tracker runs the steps: one run alone, or up to
// physics::World::kMaxSideBySide runs side by side with their worlds stepped together
// (World::stepSideBySide: the same bits, less time). To add one: a file here,
// a StrategyKind, and a line in makeStrategy().
#pragma once

#include <memory>
#include <span>

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
  // The learned detector's evidence this frame (nullptr: none or not confident): its
  // keypoints as labelled points on the bodies they name, and the model fitted to them.
  std::span<const LabelledPoint> detectorLabels;
  const model::ModelPose* detectorPose = nullptr;
  // The learned detector's keypoints are confident and on the data this frame, and the
  // detector-fit simulation is switched on (it runs when the frame starts farther than
  // DetectorSettings::engageDistanceM from them; nearer, the start already agrees with them).
  // Finger flip stands down then: the detector's fit is the data's own answer to a wrongly
  // bent finger, where the flip only guesses.
  bool detectorInUse = false;
};

class Strategy {
 public:
  virtual ~Strategy() = default;
  virtual StrategyKind kind() const = 0;
  // Physics steps of a run with `substeps` per phase (for ordering the runs side by side).
  virtual int steps(int substeps) const = 0;
  // Sets up this frame's run; false when there is nothing to do (no candidate this frame).
  virtual bool begin(StrategyContext& context) = 0;
  // Before physics step `step` (0, 1, ...) of the run: configures the world for it and
  // returns the input its rows come from; nullptr once the run is over, the world's
  // configuration then back as begin() found it.
  virtual const FrameInput* beforeStep(StrategyContext& context, int step) = 0;
};

std::unique_ptr<Strategy> makeStrategy(StrategyKind kind);

// Runs a strategy: begin(), then each step (Simulator::prepareStep, World::step) until
// beforeStep() ends the run. false when begin() was.
bool runStrategy(Strategy& strategy, StrategyContext& context);
// Runs strategies, each on its own rig and simulator, up to physics::World::kMaxSideBySide at
// a time, step by step: the runs that have a step take it together
// (physics::World::stepSideBySide); when a run ends, the next strategy in order takes its
// place. The same bits as running them one after the other. ran[i]: what strategy i's begin()
// returned.
void runStrategiesSideBySide(std::span<Strategy* const> strategies,
                             std::span<StrategyContext* const> contexts, std::span<bool> ran);

}  // namespace dynahand::track
