// TrackerSettings' fields by name (setTrackerSetting, namedSettings): what `dynahand track
// --set` and `dynahand bench --set` take.
#include <gtest/gtest.h>

#include <string>

#include "dynahand/tracker.h"

namespace dynahand::track {
namespace {

// A value other than `value` of the same kind, as text.
std::string otherValue(const std::string& value) {
  if (value == "true") return "false";
  if (value == "false") return "true";
  if (value.find_first_of(".e") == std::string::npos) return std::to_string(std::stoi(value) + 1);
  return std::to_string(std::stof(value) * 2.0f + 0.25f);
}

TEST(SettingsByName, EveryListedSettingIsSetAndNoOther) {
  const std::vector<NamedSetting> defaults = namedSettings();
  ASSERT_GE(defaults.size(), 50u);
  for (std::size_t i = 0; i < defaults.size(); ++i) {
    TrackerSettings settings;
    const std::string value = otherValue(defaults[i].value);
    ASSERT_TRUE(setTrackerSetting(settings, defaults[i].name + "=" + value)) << defaults[i].name;
    const std::vector<NamedSetting> changed = namedSettings(settings);
    ASSERT_EQ(changed.size(), defaults.size());
    for (std::size_t j = 0; j < defaults.size(); ++j) {
      if (j == i)
        EXPECT_NE(changed[j].value, defaults[j].value) << defaults[i].name;
      else
        EXPECT_EQ(changed[j].value, defaults[j].value)
            << defaults[i].name << " moved " << defaults[j].name;
    }
  }
}

TEST(SettingsByName, NamesAreTheFieldsTheDocsName) {
  TrackerSettings settings;
  ASSERT_TRUE(setTrackerSetting(settings, "detector.selectionWeight", "0"));
  EXPECT_EQ(settings.detector.selectionWeight, 0.0f);
  ASSERT_TRUE(setTrackerSetting(settings, "detector.fitStartPoseWeight=0.07"));
  EXPECT_EQ(settings.detector.fitStartPoseWeight, 0.07f);
  ASSERT_TRUE(setTrackerSetting(settings, "substeps", "3"));
  EXPECT_EQ(settings.substeps, 3);
  ASSERT_TRUE(setTrackerSetting(settings, "cloud.segmentation.handRadiusM", "0.2"));
  EXPECT_EQ(settings.cloud.segmentation.handRadiusM, 0.2f);
  ASSERT_TRUE(setTrackerSetting(settings, "detector.enabled", "false"));
  EXPECT_FALSE(settings.detector.enabled);
  ASSERT_TRUE(setTrackerSetting(settings, "detector.enabled", "1"));
  EXPECT_TRUE(settings.detector.enabled);
  // The listing's values are the settings' own: a default tracker's are the shipped ones.
  for (const NamedSetting& s : namedSettings()) {
    if (s.name == "detector.selectionWeight") {
      EXPECT_EQ(s.value, "1");
    }
  }
}

TEST(SettingsByName, ErrorsNameTheSettingAndTheValue) {
  TrackerSettings settings;
  const auto message = [&](const char* name, const char* value) {
    const Status s = setTrackerSetting(settings, name, value);
    return s ? std::string("accepted") : s.message();
  };
  EXPECT_NE(message("detector.noSuchThing", "1")
                .find("unknown tracker setting "
                      "'detector.noSuchThing'"),
            std::string::npos);
  EXPECT_NE(message("pullForce", "strong").find("pullForce: 'strong' is not a number"),
            std::string::npos);
  EXPECT_NE(message("pullForce", "nan").find("not a number"), std::string::npos);
  EXPECT_NE(message("pullForce", "inf").find("not a number"), std::string::npos);
  EXPECT_NE(message("pullForce", "7000N").find("not a number"), std::string::npos);
  EXPECT_NE(message("substeps", "2.5").find("substeps: '2.5' is not a whole number"),
            std::string::npos);
  EXPECT_NE(message("perFrame", "yes").find("perFrame: 'yes' is not true or false"),
            std::string::npos);
  const Status noValue = setTrackerSetting(settings, "substeps");
  ASSERT_FALSE(noValue);
  EXPECT_NE(noValue.message().find("expected NAME=VALUE"), std::string::npos);
  // Nothing was changed by the refused values.
  EXPECT_EQ(namedSettings(settings).size(), namedSettings().size());
  for (std::size_t i = 0; i < namedSettings().size(); ++i)
    EXPECT_EQ(namedSettings(settings)[i].value, namedSettings()[i].value);
}

}  // namespace
}  // namespace dynahand::track
