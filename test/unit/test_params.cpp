// The parameter table: config/acvo.yaml carries the struct's defaults, every key is wired, and
// mistakes in a YAML file are reported with the file and the key.
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <type_traits>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "acvo/params.hpp"
#include "test_support.hpp"

namespace acvo {
namespace {

// Every parameter as "section.name" -> exact text (doubles in hexadecimal, so equal text means
// equal bits).
std::map<std::string, std::string> flatten(const Params& p) {
  std::map<std::string, std::string> out;
  visitParams(p, [&out](const char* section, const char* name, const auto& field) {
    using T = std::decay_t<decltype(field)>;
    std::string text;
    if constexpr (std::is_enum_v<T>) {
      text = toString(field);
    } else if constexpr (std::is_same_v<T, bool>) {
      text = field ? "true" : "false";
    } else if constexpr (std::is_same_v<T, int>) {
      text = std::to_string(field);
    } else {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%a", field);
      text = buf;
    }
    out[std::string(section) + "." + name] = text;
  });
  return out;
}

std::string expectThrowMessage(const std::string& yaml) {
  try {
    parseParams(yaml, Params(), "test.yaml");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no exception for:\n" << yaml;
  return {};
}

TEST(Params, ConfigFileHoldsEveryKeyWithTheStructDefaults) {
  const std::string path = (test::sourceDir() / "config" / "acvo.yaml").string();
  const Params loaded = loadParams(path);
  const auto got = flatten(loaded);
  const auto want = flatten(Params());
  ASSERT_EQ(got.size(), 75u);  // every parameter of visitParams
  EXPECT_EQ(got, want);
  // Equal values could also come from keys missing in the file: check that each key of the
  // sections the default engine reads is written, and that the other engine's is not there.
  const YAML::Node file = YAML::LoadFile(path);
  EXPECT_FALSE(file["paper"]) << "the paper engine's section belongs to paper.yaml";
  visitParams(loaded, [&file](const char* section, const char* name, const auto&) {
    if (std::string(section) == "paper") return;
    EXPECT_TRUE(file[section] && file[section][name]) << section << "." << name << " missing";
  });
}

// The paper's A-CVO and CVO are one file away each: config/paper.yaml is paperParams(),
// config/cvo.yaml cvoParams(), every key written.
TEST(Params, PaperAndCvoFilesHoldEveryKeyWithTheirParams) {
  for (const auto& [file_name, expected] :
       {std::pair{"paper.yaml", paperParams()}, std::pair{"cvo.yaml", cvoParams()}}) {
    SCOPED_TRACE(file_name);
    const std::string path = (test::sourceDir() / "config" / file_name).string();
    const Params loaded = loadParams(path);
    EXPECT_EQ(flatten(loaded), flatten(expected));
    EXPECT_EQ(loaded.registration.engine, Engine::kPaper);
    EXPECT_DOUBLE_EQ(loaded.paper.sparsification, 8.315e-3);
    const YAML::Node file = YAML::LoadFile(path);
    EXPECT_FALSE(file["coarse_to_fine"]) << "the default engine's section belongs to acvo.yaml";
    visitParams(loaded, [&file](const char* section, const char* name, const auto&) {
      if (std::string(section) == "coarse_to_fine") return;
      EXPECT_TRUE(file[section] && file[section][name]) << section << "." << name << " missing";
    });
  }
  EXPECT_EQ(paperParams().paper.ell_policy, EllPolicy::kAdaptive);
  EXPECT_EQ(cvoParams().paper.ell_policy, EllPolicy::kFixedSchedule);
}

// The section that held both engines' parameters is gone: a file that still has it is told
// where its keys went.
TEST(Params, OldSolverSectionIsRejectedWithWhereItsKeysWent) {
  const std::string msg = expectThrowMessage("solver:\n  ell_min: 0.01\n");
  EXPECT_NE(msg.find("registration.engine"), std::string::npos) << msg;
  EXPECT_NE(msg.find("coarse_to_fine"), std::string::npos) << msg;
}

TEST(Params, EveryKeyIsReadIntoItsField) {
  const Params defaults;
  visitParams(defaults, [&defaults](const char* section, const char* name, const auto& field) {
    using T = std::decay_t<decltype(field)>;
    std::string value;
    if constexpr (std::is_same_v<T, Engine>) {
      value = toString(field == Engine::kPaper ? Engine::kCoarseToFine : Engine::kPaper);
    } else if constexpr (std::is_same_v<T, EllPolicy>) {
      value = toString(field == EllPolicy::kAdaptive ? EllPolicy::kFixedSchedule
                                                     : EllPolicy::kAdaptive);
    } else if constexpr (std::is_same_v<T, EllUpdate>) {
      value = toString(field == EllUpdate::kDescent ? EllUpdate::kReference : EllUpdate::kDescent);
    } else if constexpr (std::is_same_v<T, InitialGuess>) {
      value = toString(field == InitialGuess::kIdentity ? InitialGuess::kConstantVelocity
                                                        : InitialGuess::kIdentity);
    } else if constexpr (std::is_same_v<T, Reference>) {
      value = toString(field == Reference::kKeyframe ? Reference::kPreviousFrame
                                                     : Reference::kKeyframe);
    } else if constexpr (std::is_same_v<T, SyncDepth>) {
      value = toString(field == SyncDepth::kNone ? SyncDepth::kOwnMotion : SyncDepth::kNone);
    } else if constexpr (std::is_same_v<T, UnregisteredColour>) {
      value = toString(field == UnregisteredColour::kAsGiven ? UnregisteredColour::kResample
                                                             : UnregisteredColour::kAsGiven);
    } else if constexpr (std::is_same_v<T, bool>) {
      value = field ? "false" : "true";
    } else if constexpr (std::is_same_v<T, int>) {
      value = std::to_string(field + 1);
    } else {
      char buf[64];
      // Stays valid for every field (a 0 that means "off" becomes 0.5).
      std::snprintf(buf, sizeof buf, "%.17g", field == 0.0 ? 0.5 : field * 1.01);
      value = buf;
    }
    const std::string key = std::string(section) + "." + name;
    const Params p =
        parseParams(std::string(section) + ":\n  " + name + ": " + value + "\n", defaults);
    auto changed = flatten(p);
    auto original = flatten(defaults);
    EXPECT_NE(changed[key], original[key]) << key << " was not read";
    changed.erase(key);
    original.erase(key);
    EXPECT_EQ(changed, original) << key << " changed another field";
  });
}

TEST(Params, ValuesOverrideTheBase) {
  const Params p = parseParams(
      "selection:\n  target_points: 1500\n  canny_fallback: false\n"
      "  scale_with_image: false\n"
      "paper:\n  ell_update: descent\n  color_ell: 0.1\n"
      "odometry:\n  initial_guess: identity\n  threads: 2\n");
  EXPECT_EQ(p.selection.target_points, 1500);
  EXPECT_FALSE(p.selection.canny_fallback);
  EXPECT_FALSE(p.selection.scale_with_image);
  EXPECT_TRUE(Params().selection.scale_with_image);
  EXPECT_FALSE(acvo::paperParams().selection.scale_with_image);
  EXPECT_EQ(p.paper.ell_update, EllUpdate::kDescent);
  EXPECT_DOUBLE_EQ(p.paper.color_ell, 0.1);
  EXPECT_EQ(p.odometry.initial_guess, InitialGuess::kIdentity);
  EXPECT_EQ(p.odometry.threads, 2);
  EXPECT_DOUBLE_EQ(p.paper.ell_init, Params().paper.ell_init);
  // An empty text keeps the base.
  EXPECT_EQ(flatten(parseParams("", p)), flatten(p));
}

TEST(Params, UnknownKeyIsRejectedByName) {
  const std::string msg = expectThrowMessage("paper:\n  ell_initial: 0.1\n");
  EXPECT_NE(msg.find("paper.ell_initial"), std::string::npos) << msg;
  EXPECT_NE(msg.find("test.yaml"), std::string::npos) << msg;
  // A key of another section is unknown in this one.
  const std::string other = expectThrowMessage("selection:\n  sigma: 0.1\n");
  EXPECT_NE(other.find("selection.sigma"), std::string::npos) << other;
  // One engine's knob is unknown to the other's section.
  const std::string engine = expectThrowMessage("coarse_to_fine:\n  ell_max: 0.1\n");
  EXPECT_NE(engine.find("coarse_to_fine.ell_max"), std::string::npos) << engine;
}

TEST(Params, UnknownSectionIsRejectedByName) {
  const std::string msg = expectThrowMessage("slover:\n  sigma: 0.1\n");
  EXPECT_NE(msg.find("slover"), std::string::npos) << msg;
  EXPECT_NE(msg.find("test.yaml"), std::string::npos) << msg;
}

TEST(Params, WrongTypesAreRejectedByName) {
  const std::map<std::string, std::string> cases = {
      {"selection:\n  target_points: lots\n", "selection.target_points"},
      {"selection:\n  target_points: 2.5\n", "selection.target_points"},
      {"selection:\n  canny_fallback: 3\n", "selection.canny_fallback"},
      {"coarse_to_fine:\n  sigma: abc\n", "coarse_to_fine.sigma"},
      {"paper:\n  sigma: [0.1, 0.2]\n", "paper.sigma"},
      {"paper:\n  ell_policy: sideways\n", "paper.ell_policy"},
      {"registration:\n  engine: icp\n", "registration.engine"},
      {"odometry:\n  initial_guess: 1\n", "odometry.initial_guess"},
      {"paper: 3\n", "paper"},
      {"- a\n- b\n", "sections"},
  };
  for (const auto& [yaml, key] : cases) {
    const std::string msg = expectThrowMessage(yaml);
    EXPECT_NE(msg.find(key), std::string::npos) << yaml << " -> " << msg;
  }
  const std::string msg = expectThrowMessage("paper:\n  ell_policy: sideways\n");
  EXPECT_NE(msg.find("fixed_schedule"), std::string::npos) << "accepted values listed: " << msg;
  const std::string engine = expectThrowMessage("registration:\n  engine: icp\n");
  EXPECT_NE(engine.find("coarse_to_fine"), std::string::npos) << engine;
}

TEST(Params, LoadNamesTheFile) {
  const auto dir = test::tempDir("params");
  const std::string path = (dir / "bad.yaml").string();
  std::ofstream(path) << "paper:\n  ell_min: 0.2\n  ell_max: 0.1\n";
  try {
    loadParams(path);
    ADD_FAILURE() << "inconsistent file accepted";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find("ell_min"), std::string::npos) << msg;
  }
  const std::string missing = (dir / "missing.yaml").string();
  try {
    loadParams(missing);
    ADD_FAILURE() << "missing file accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
  const std::string broken = (dir / "broken.yaml").string();
  std::ofstream(broken) << "paper: [unclosed\n";
  EXPECT_THROW(loadParams(broken), std::runtime_error);
}

TEST(Params, EnumStringsRoundTrip) {
  for (EllPolicy v : {EllPolicy::kAdaptive, EllPolicy::kFixedSchedule}) {
    EllPolicy back = v == EllPolicy::kAdaptive ? EllPolicy::kFixedSchedule : EllPolicy::kAdaptive;
    fromString(toString(v), back);
    EXPECT_EQ(back, v);
  }
  for (EllUpdate v : {EllUpdate::kDescent, EllUpdate::kReference}) {
    EllUpdate back = v == EllUpdate::kDescent ? EllUpdate::kReference : EllUpdate::kDescent;
    fromString(toString(v), back);
    EXPECT_EQ(back, v);
  }
  for (InitialGuess v : {InitialGuess::kConstantVelocity, InitialGuess::kIdentity}) {
    InitialGuess back =
        v == InitialGuess::kIdentity ? InitialGuess::kConstantVelocity : InitialGuess::kIdentity;
    fromString(toString(v), back);
    EXPECT_EQ(back, v);
  }
  for (Reference v : {Reference::kKeyframe, Reference::kPreviousFrame}) {
    Reference back = v == Reference::kKeyframe ? Reference::kPreviousFrame : Reference::kKeyframe;
    fromString(toString(v), back);
    EXPECT_EQ(back, v);
  }
  EXPECT_EQ(toString(Reference::kKeyframe), "keyframe");
  EXPECT_EQ(toString(Reference::kPreviousFrame), "previous_frame");
  for (Engine v : {Engine::kCoarseToFine, Engine::kPaper}) {
    Engine back = v == Engine::kPaper ? Engine::kCoarseToFine : Engine::kPaper;
    fromString(toString(v), back);
    EXPECT_EQ(back, v);
  }
  EXPECT_EQ(toString(Engine::kCoarseToFine), "coarse_to_fine");
  EXPECT_EQ(toString(Engine::kPaper), "paper");
  EXPECT_EQ(toString(EllPolicy::kAdaptive), "adaptive");
  EXPECT_EQ(toString(EllPolicy::kFixedSchedule), "fixed_schedule");
  EXPECT_EQ(toString(EllUpdate::kDescent), "descent");
  EXPECT_EQ(toString(EllUpdate::kReference), "reference");
  EXPECT_EQ(toString(InitialGuess::kConstantVelocity), "constant_velocity");
  EXPECT_EQ(toString(InitialGuess::kIdentity), "identity");
  EllUpdate u = EllUpdate::kDescent;
  EXPECT_THROW(fromString("Reference", u), std::invalid_argument);
  EXPECT_EQ(u, EllUpdate::kDescent);
}

TEST(Params, ValidateCatchesInconsistentValues) {
  EXPECT_EQ(validate(Params()), "");
  auto message = [](auto change) {
    Params p;
    change(p);
    return validate(p);
  };
  EXPECT_NE(message([](Params& p) { p.paper.ell_min = 0.2; }).find("paper.ell_min"),
            std::string::npos);
  EXPECT_NE(message([](Params& p) { p.coarse_to_fine.ell_min = 0.2; })
                .find("coarse_to_fine.ell_init"),
            std::string::npos);
  EXPECT_NE(message([](Params& p) { p.coarse_to_fine.sigma = 0.0; }).find("coarse_to_fine.sigma"),
            std::string::npos);
  EXPECT_NE(message([](Params& p) { p.paper.sigma = -0.1; }).find("paper.sigma"),
            std::string::npos);
  EXPECT_NE(message([](Params& p) { p.paper.color_sigma = 0.0; }).find("color_sigma"),
            std::string::npos);
  EXPECT_NE(message([](Params& p) { p.coarse_to_fine.level_acceleration = 1.0; })
                .find("level_acceleration"),
            std::string::npos);
  EXPECT_NE(message([](Params& p) { p.selection.target_points = 0; }).find("target_points"),
            std::string::npos);
  EXPECT_NE(message([](Params& p) { p.selection.target_points = -5; }).find("target_points"),
            std::string::npos);
  EXPECT_NE(message([](Params& p) { p.selection.min_depth = 16.0; }).find("min_depth"),
            std::string::npos);
  EXPECT_NE(message([](Params& p) { p.selection.min_depth = 17.0; }).find("min_depth"),
            std::string::npos);
  EXPECT_NE(message([](Params& p) {
              p.paper.ell_init = std::numeric_limits<double>::quiet_NaN();
            }).find("paper.ell_init"),
            std::string::npos);
  EXPECT_NE(message([](Params& p) { p.paper.max_step = 0.1; }).find("min_step"),
            std::string::npos);
  EXPECT_NE(message([](Params& p) { p.odometry.threads = -2; }).find("threads"), std::string::npos);
  EXPECT_NE(message([](Params& p) { p.odometry.window_keyframes = -1; })
                .find("odometry.window_keyframes"),
            std::string::npos);
  EXPECT_NE(message([](Params& p) { p.odometry.keyframe_matched_fraction = 1.5; })
                .find("odometry.keyframe_matched_fraction"),
            std::string::npos);
  EXPECT_NE(message([](Params& p) { p.odometry.keyframe_translation = 0.0; })
                .find("odometry.keyframe_translation"),
            std::string::npos);
  EXPECT_NE(message([](Params& p) { p.odometry.lost_speed = -1.0; }).find("odometry.lost_speed"),
            std::string::npos);
  for (const double exposure : {-0.001, 1.5, std::numeric_limits<double>::quiet_NaN()}) {
    EXPECT_NE(message([exposure](Params& p) { p.coarse_to_fine.exposure_time = exposure; })
                  .find("coarse_to_fine.exposure_time"),
              std::string::npos)
        << exposure;
  }
  EXPECT_EQ(message([](Params& p) { p.coarse_to_fine.exposure_time = 0.0; }), "");
  // The YAML loader applies the same checks.
  const std::string msg = expectThrowMessage("coarse_to_fine:\n  sigma: -1\n");
  EXPECT_NE(msg.find("coarse_to_fine.sigma"), std::string::npos) << msg;
}

}  // namespace
}  // namespace acvo

namespace acvo {
namespace {

// What a log shows: every parameter once, by section and name, and the ones that differ.
TEST(Params, DescribeChangesNamesWhatDiffers) {
  const Params p;
  const auto texts = paramTexts(p, '/');
  std::size_t fields = 0;
  visitParams(p, [&](const char*, const char*, const auto&) { ++fields; });
  ASSERT_EQ(texts.size(), fields);
  EXPECT_EQ(texts.front().first, "selection/target_points");
  EXPECT_EQ(texts.front().second, "4000");
  EXPECT_EQ(describeChanges(p, p), "");
  Params q = p;
  q.coarse_to_fine.photometric = false;
  q.coarse_to_fine.depth_noise = 0.001;
  q.odometry.sync_depth = SyncDepth::kNone;
  EXPECT_EQ(describeChanges(p, q),
            "coarse_to_fine.depth_noise=0.001 coarse_to_fine.photometric=false "
            "odometry.sync_depth=none");
  EXPECT_EQ(describeChanges(q, p, '/'),
            "coarse_to_fine/depth_noise=0.0025000000000000001 coarse_to_fine/photometric=true "
            "odometry/sync_depth=own_motion");
}

}  // namespace
}  // namespace acvo
