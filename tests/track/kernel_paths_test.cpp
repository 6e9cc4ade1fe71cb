// The tracker's output bytes do not depend on which path its vector kernels take: every
// kernel with a vector and a narrower path (physics: surface-row preparation and sweeps;
// error metric: the bulk queries against the one-point ones; the SIMD layer's kernels) is forced
// to its narrow path in turn, then all at once, and every level of the SIMD layer in turn, and
// the standard clips must track to the same bits as with every fast path the CPU has. Paths the
// CPU lacks are narrow already: the comparison then covers fewer of them (the test says which).
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "core/simd/simd.h"
#include "dynahand/core.h"
#include "dynahand/synth.h"
#include "dynahand/tracker.h"
#include "physics/kernel_paths.h"
#include "track/posed_bodies.h"

namespace dynahand::track {
namespace {

constexpr int kFrames = 20;

// Every kernel's fast path on (where the CPU has it) but `narrow` (bit i: path i forced
// narrow, in the order of kPathNames); returns which fast paths are in use.
constexpr const char* kPathNames[] = {"surface prepare (8 lanes)", "surface sweeps (batches)",
                                      "error metric's bulk queries",
                                      "SIMD layer kernels (core/simd, widest level)"};
unsigned choosePaths(unsigned narrow) {
  unsigned fast = 0;
  // The level first: the sweeps run in batches only above the scalar level.
  const simd::Level level = (narrow & 8u) == 0 ? simd::bestLevel() : simd::Level::Scalar;
  fast |= simd::forceLevel(level) != simd::Level::Scalar ? 8u : 0u;
  fast |= physics::useWideSurfacePrepare((narrow & 1u) == 0) ? 1u : 0u;
  fast |= physics::useVectorSweeps((narrow & 2u) == 0) ? 2u : 0u;
  fast |= PosedBodies::useBulkQueries((narrow & 4u) == 0) ? 4u : 0u;
  return fast;
}

// FNV-1a of every frame's winning pose, keypoints and error over the standard clips.
std::uint64_t trackStandardClips(const std::vector<synth::SyntheticSequence*>& clips,
                                 const TrackerSettings& settings = {}) {
  Fnv1a h;
  for (synth::SyntheticSequence* seq : clips) {
    auto tracker = Tracker::create(seq->model(0), seq->intrinsics(), settings);
    EXPECT_TRUE(tracker.ok());
    if (!tracker) return 0;
    for (int f = 0; f < kFrames; ++f) {
      const auto& frame = seq->frame(f);
      if (f == 0) (*tracker)->initialize(frame.hands[0].pose);
      const HandResult& hand = (*tracker)->track(frame.depth).hands[0];
      for (const Pose& p : hand.pose.bodies) h.add(p);
      for (const Vec3& k : hand.keypoints21) h.add(k);
      h.add(hand.error);
    }
  }
  return h.value();
}

std::vector<synth::SyntheticSequence> standardClips() {
  std::vector<synth::SyntheticSequence> sequences;
  for (const std::string& clip : synth::defaultClipSet()) {
    synth::SynthOptions o;
    o.clip = clip;
    o.profile = "tof";
    o.frameCount = kFrames;
    auto seq = synth::SyntheticSequence::create(o);
    EXPECT_TRUE(seq.ok()) << seq.error().message;
    if (seq) sequences.push_back(std::move(*seq));
  }
  return sequences;
}

TEST(KernelPaths, EveryPathTracksTheStandardClipsToTheSameBytes) {
  std::vector<synth::SyntheticSequence> sequences = standardClips();
  ASSERT_EQ(sequences.size(), synth::defaultClipSet().size());
  std::vector<synth::SyntheticSequence*> clips;
  for (auto& s : sequences) clips.push_back(&s);

  const unsigned fast = choosePaths(0);
  const std::uint64_t reference = trackStandardClips(clips);
  for (unsigned path = 0; path < std::size(kPathNames); ++path) {
    const unsigned bit = 1u << path;
    if ((fast & bit) == 0) {
      std::printf("%s: not on this CPU, narrow already\n", kPathNames[path]);
      continue;
    }
    choosePaths(bit);
    EXPECT_EQ(trackStandardClips(clips), reference) << kPathNames[path] << " forced narrow";
  }
  choosePaths(~0u);
  EXPECT_EQ(trackStandardClips(clips), reference) << "every path forced narrow";
  EXPECT_EQ(choosePaths(0), fast);  // the defaults again
  // Every level of the SIMD layer in turn (scalar, SSE2, AVX2, AVX-512, as far as the CPU
  // goes).
  for (int l = 0; l < static_cast<int>(simd::bestLevel()); ++l) {
    const auto level = static_cast<simd::Level>(l);
    ASSERT_EQ(simd::forceLevel(level), level);
    EXPECT_EQ(trackStandardClips(clips), reference) << "SIMD level " << simd::levelName(level);
  }
  simd::forceLevel(simd::bestLevel());
}

// The tracker's output on the standard clips without the learned detector (whose OpenCV kernels
// sum in a CPU-dependent order), pinned: any change of the tracker's behaviour changes this
// hash. When a change is meant to change the results (and the benchmarks say it is better),
// re-baseline kGoldenHash to the value the failure prints, in the same commit.
TEST(Golden, StandardClipsWithoutTheDetector) {
  constexpr std::uint64_t kGoldenHash = 0x57361ef9ed126a8b;
  std::vector<synth::SyntheticSequence> sequences = standardClips();
  ASSERT_EQ(sequences.size(), synth::defaultClipSet().size());
  std::vector<synth::SyntheticSequence*> clips;
  for (auto& s : sequences) clips.push_back(&s);
  TrackerSettings settings;
  settings.detector.enabled = false;
  const std::uint64_t hash = trackStandardClips(clips, settings);
  EXPECT_EQ(hash, kGoldenHash) << "the tracker's output changed: 0x" << std::hex << hash;
}

}  // namespace
}  // namespace dynahand::track
