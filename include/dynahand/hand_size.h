/// @file
/// Automatic hand-size estimate (beyond the paper): which size of the default hand
/// (model::makeDefaultHand) best explains the first second or so of a depth sequence.
///
/// Measuring the hand in the data while tracking it with a model of the wrong size does not
/// work: the tracker bends a too-long finger and keeps the palm's samples within the model's
/// width, so such measures stay near the model's size. Instead, candidate models are each
/// tracked over the same frames from the same start and scored by how well they explain the
/// data both ways: the harmonic mean of the share of the hand's samples within 10 mm of the
/// model (low when the model is too small) and the share of the model's visible surface on
/// the segmented hand (low when it is too big) (FitQuality, tracker.h). The search:
///   1. uniform scale of the default proportions, 0.80-1.20 in steps of 0.10, then the two
///      half steps beside the best, and the peak of a parabola through the best three;
///   2. width alone at that length (-7 %, 0, +7 %), parabola peak;
///   3. length alone at that width (-8 %, 0, +8 %), parabola peak, scored only over the frames
///      where the fingers are out straight: a too-long finger curls into a fist as well as
///      the right one.
///   4. each digit's metacarpal length (where its knuckle, or the thumb's base, sits on the
///      palm; HandShape::boneLength[digit][0]), +-10 % then +-5 % about the estimate so far,
///      parabola peak, half of it kept. Scored by the paper's error metric with every
///      candidate started afresh on each frame from the estimate's tracked keypoints (runs of
///      hands a few percent apart drift apart by chance), and only on frames where the palm
///      faces the camera: seen from behind the metric prefers long metacarpals whatever the
///      hand, so from a head-mounted camera the shape stays the default.
/// Seen from behind (the learned detector's keypoints show the palm facing the camera on fewer
/// than 8 of the frames it ran on, at least 8), steps 1-3 are replaced: the size is the default
/// proportions scaled to the detector's palm (median wrist-to-knuckle length), since there the
/// data explain a hand's back about as well at any size near the truth (the search ran 6-11 %
/// long from a head-mounted camera); 1 candidate tracked for the score.
/// 13 candidate trackers for the size; for the shape (HandSizeOptions::metacarpals) 12 per
/// step, 1 (the reference) when fewer than 8 frames show the palm; they run in parallel on
/// `threads`. A length or width the caller gives is kept: then step 1
/// scales the other alone and steps 2-3 are left out (7 trackers; a length searched so scores
/// every frame, fists included); both given, only step 4.
/// Measured figures: docs/tracker.md, "Hand size".
#pragma once

#include <optional>
#include <span>

#include "dynahand/depth_frame.h"
#include "dynahand/model.h"
#include "dynahand/tracker.h"

namespace dynahand::track {

/// How estimateHandSize searches.
struct HandSizeOptions {
  TrackerSettings tracker;  ///< settings of the candidate trackers (candidates are not kept)
  /// Without start keypoints: the default hand's tracker (a given length or width, the other in
  /// the default proportion), with the learned detector (unless tracker.detector is off), runs
  /// over the frames (only the first acquisitionFrames when a dimension is given), and the
  /// candidates start from the keypoints it reports on the first of the first acquisitionFrames
  /// frames where it has the hand with a detection in use; they are scored from that frame on.
  /// Found in none of them: each candidate acquires the hand by itself (the paper's canonical
  /// starts: an open hand facing the camera) and leaves these frames out of its score, since
  /// acquisition may take a few frames and a candidate slow to acquire is not a worse size.
  /// With start keypoints every frame counts.
  int acquisitionFrames = 6;
  int threads = 1;  ///< candidate trackers run in parallel; the result does not depend on it
  /// m: a known length, kept (only the width is estimated; with a width too, only the
  /// metacarpals). The detected start's hand has it, the width in the default proportion.
  std::optional<float> length;
  std::optional<float> width;  ///< m: a known width, kept (as length)
  /// Also estimate each digit's metacarpal length (step 4); false: the default shape (then
  /// length and width both given leave nothing to estimate: an error).
  bool metacarpals = true;
};

/// The result of estimateHandSize.
struct HandSizeEstimate {
  model::HandDimensions dimensions;  ///< the estimate, m
  /// The estimated shape: each digit's metacarpal length factor (boneLength[digit][0]; all 1
  /// when too few frames show the palm or HandSizeOptions::metacarpals is off), every other
  /// factor 1. The hand to track is
  /// model::makeDefaultHand(dimensions, side, shape).
  model::HandShape shape;
  int framesUsed = 0;  ///< frames each candidate tracked
  int candidates = 0;  ///< candidate models tracked
  /// The best candidate's score: mean over the scored frames of the harmonic mean of
  /// FitQuality::dataNearModel and FitQuality::modelOnHand (0 in frames where it lost the
  /// hand), [0, 1]. About 0.98-0.99 on clean synthetic data; low values mean the estimate is
  /// unreliable.
  float fitScore = 0.0f;
};

/// Estimates the hand size from `frames` (the start of a sequence, e.g. 30 frames; without
/// start keypoints more than acquisitionFrames). start: the first frame's 21 keypoints (each
/// candidate is fitted to them under its joint limits), or none: the start then comes from the
/// learned detector (HandSizeOptions::acquisitionFrames). Errors for bad intrinsics or too few
/// frames.
Result<HandSizeEstimate> estimateHandSize(std::span<const DepthFrame> frames,
                                          const Intrinsics& intrinsics,
                                          const std::optional<Keypoints21>& start,
                                          const HandSizeOptions& options = {});

}  // namespace dynahand::track
