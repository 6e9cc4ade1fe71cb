// The standard suite's composition and how its results are grouped into rows and tables
// (without tracking: the results here are made up, their per-clip means only).
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "dynahand/synth.h"
#include "dynahand/tools/bench_suite.h"

namespace dynahand::eval {
namespace {

TEST(BenchSuite, AblationsAlsoRunTheClipsTheStrategiesTarget) {
  const std::vector<SuiteItem> items = standardSuite({});
  const auto& defaults = synth::defaultClipSet();
  int standard = 0, ablations = 0;
  std::set<std::string> variantsOfTargeted[3];
  for (const SuiteItem& item : items) {
    if (!item.ablation) {
      ++standard;
      continue;
    }
    ++ablations;
    const auto& targeted = targetedAblationClips();
    const auto t = std::find(targeted.begin(), targeted.end(), item.clip);
    ASSERT_EQ(item.targeted, t != targeted.end()) << item.clip;
    if (item.targeted)
      variantsOfTargeted[t - targeted.begin()].insert(item.variant);
    else
      EXPECT_NE(std::find(defaults.begin(), defaults.end(), item.clip), defaults.end());
    EXPECT_EQ(item.profile, "tof");
    EXPECT_EQ(item.size.name, "medium");
    EXPECT_FALSE(item.autoInit);
  }
  // 3 sizes x 4 profiles x 2 starts x the default clips; each strategy off and normal only
  // on the default clips (their baseline is the standard tof / medium / gt item), and "all"
  // besides on each targeted clip.
  const int variants = track::kStrategyCount + 1;
  EXPECT_EQ(standard, 3 * 4 * 2 * static_cast<int>(defaults.size()));
  EXPECT_EQ(ablations, variants * static_cast<int>(defaults.size()) + (variants + 1) * 3);
  for (const auto& targetedVariants : variantsOfTargeted) {
    EXPECT_EQ(targetedVariants.size(), static_cast<std::size_t>(variants + 1));
    EXPECT_TRUE(targetedVariants.contains("all") && targetedVariants.contains("no finger_flip") &&
                targetedVariants.contains("normal only"));
  }
  // The quick suite (CI) has no targeted clips.
  for (const SuiteItem& item : standardSuite({.quick = true})) EXPECT_FALSE(item.targeted);
}

SuiteItemResult madeUp(const SuiteItem& item, double meanMm) {
  SuiteItemResult r;
  r.item = item;
  r.metrics.meanMm = meanMm;
  r.metrics.successFraction = {1.0, 1.0, 1.0, 1.0, 1.0};
  r.frameMs = {1.0};
  r.frameCpuMs = {1.0};
  return r;
}

TEST(BenchSuite, TargetedClipsAppearInThePerClipTableOnly) {
  SuiteItem baseline;
  baseline.clip = "wave";
  baseline.profile = "tof";
  baseline.size = benchHandSizes()[1];
  SuiteItem noFlip = baseline;
  noFlip.ablation = true;
  noFlip.variant = "no finger_flip";
  SuiteItem targetedAll = noFlip;
  targetedAll.variant = "all";
  targetedAll.targeted = true;
  targetedAll.clip = "finger-flips";
  SuiteItem targetedNoFlip = targetedAll;
  targetedNoFlip.variant = "no finger_flip";
  const std::vector<SuiteItemResult> results = {madeUp(baseline, 3.0), madeUp(noFlip, 3.5),
                                                madeUp(targetedAll, 8.0),
                                                madeUp(targetedNoFlip, 46.0)};
  std::vector<std::string> labels;
  for (const SuiteRow& row : summarizeSuite(results)) labels.push_back(row.label);
  EXPECT_EQ(labels,
            (std::vector<std::string>{"tof / medium / gt", "ablation: all (= tof / medium / gt)",
                                      "ablation: no finger_flip"}));
  const std::string table = ablationByClipMarkdown(results);
  EXPECT_NE(table.find("| wave | 3.0 (100%) | 3.5 (100%) |"), std::string::npos) << table;
  EXPECT_NE(table.find("| finger-flips | 8.0 (100%) | 46.0 (100%) |"), std::string::npos) << table;
}

}  // namespace
}  // namespace dynahand::eval
