// The generated header of test/example_settings.yaml: defaults, keys, the YAML loader's checks, and
// dynamic_reconfigure's message applied to the live settings.
#include <docking_settings/example_importer.h>
#include <docking_settings/example_settings.h>
#include <docking_settings/reconfigure.h>
#include <docking_settings/yaml_loader.h>
#include <gtest/gtest.h>

#include <map>

using docking_settings::ConfigError;
using docking_settings::ConfigProblem;
using docking_settings::SettingInfo;
using docking_settings::example::ExampleSettings;

TEST(GeneratedSettings, DefaultsComeFromTheDeclaration) {
  const ExampleSettings s;
  EXPECT_DOUBLE_EQ(s.rate_hz, 50.0);
  EXPECT_EQ(s.count, 3);
  EXPECT_TRUE(s.enabled);
  EXPECT_EQ(s.names, (std::vector<std::string>{"a", "b", "c"}));
  EXPECT_EQ(s.widths, (std::vector<int>{4, 8}));
  EXPECT_DOUBLE_EQ(s.inner.gain, 0.5);
  EXPECT_EQ(s.wheels.mode, "fast");
}

TEST(GeneratedSettings, EveryKeyIsVisitedWithItsPrefixAndDeclaration) {
  ExampleSettings s;
  std::map<std::string, const SettingInfo*> seen;
  docking_settings::example::visitSettings(s, [&](const SettingInfo& info, const std::string& key, auto&) {
    seen[key] = &info;
  });
  EXPECT_EQ(seen.size(), 10u);
  ASSERT_TRUE(seen.count("inner_gain"));
  ASSERT_TRUE(seen.count("wheels/mode"));
  EXPECT_TRUE(seen["inner_gain"]->live);
  EXPECT_DOUBLE_EQ(seen["inner_gain"]->max, 1.0);
  EXPECT_STREQ(seen["rate_hz"]->unit, "Hz");
  EXPECT_STREQ(seen["ceiling_m"]->testbed, "the lab's ceiling height");
  EXPECT_EQ(seen["wheels/mode"]->choices, (std::vector<std::string>{"fast", "slow"}));
  EXPECT_EQ(seen["names"]->size, 3);
}

TEST(GeneratedSettings, AYamlFileOverridesTheDefaultsAndItsUnreadKeysAreNamed) {
  ExampleSettings s;
  const auto unread = docking_settings::loadSettingsYaml(EXAMPLE_DIR "/example_override.yaml", s);
  EXPECT_DOUBLE_EQ(s.rate_hz, 100.0);
  EXPECT_DOUBLE_EQ(s.inner.gain, 0.25);
  EXPECT_DOUBLE_EQ(s.wheels.gain, 0.5);
  EXPECT_EQ(s.wheels.mode, "slow");
  EXPECT_EQ(unread, (std::set<std::string>{"unknown_key"}));
  EXPECT_THROW(docking_settings::shippedSettings<ExampleSettings>(EXAMPLE_DIR "/example_override.yaml"), ConfigError);
}

TEST(GeneratedSettings, AValueOutsideItsDeclarationIsRefusedWithItsKey) {
  try {
    docking_settings::shippedSettings<ExampleSettings>(EXAMPLE_DIR "/example_wrong.yaml");
    FAIL() << "accepted inner_gain 1.5";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.problem(), ConfigProblem::kOutOfRange);
    EXPECT_NE(e.key().find("inner_gain"), std::string::npos) << e.key();
  }
}

TEST(GeneratedSettings, ReconfigureSetsOnlyTheLiveSettings) {
  ExampleSettings s;
  dynamic_reconfigure::Config config;
  dynamic_reconfigure::DoubleParameter gain;
  gain.name = "inner_gain";
  gain.value = 0.75;
  dynamic_reconfigure::DoubleParameter rate;  // not live: ignored
  rate.name = "rate_hz";
  rate.value = 20.0;
  dynamic_reconfigure::StrParameter mode;
  mode.name = "inner_mode";
  mode.value = "slow";
  dynamic_reconfigure::IntParameter count;
  count.name = "count";
  count.value = 7;
  config.doubles = {gain, rate};
  config.strs = {mode};
  config.ints = {count};
  EXPECT_EQ(docking_settings::applyReconfigure(config, s), 3);
  EXPECT_DOUBLE_EQ(s.inner.gain, 0.75);
  EXPECT_EQ(s.inner.mode, "slow");
  EXPECT_EQ(s.count, 7);
  EXPECT_DOUBLE_EQ(s.rate_hz, 50.0);
}

TEST(GeneratedSettings, AnImportedStructIsVisitedUnderItsPrefix) {
  docking_settings::example::ImporterSettings s;
  EXPECT_DOUBLE_EQ(s.retry.initial_s, 0.5);
  std::map<std::string, double> seen;
  docking_settings::example::visitSettings(s, [&](const SettingInfo&, const std::string& key, auto& field) {
    if constexpr (std::is_same_v<std::decay_t<decltype(field)>, double>) seen[key] = field;
  });
  EXPECT_EQ(seen, (std::map<std::string, double>{{"rate_hz", 15.0}, {"retry/initial_s", 0.5}, {"retry/factor", 2.0}}));
}
