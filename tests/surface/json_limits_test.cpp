// The limits of reading scene files (zeroset/surface/json_read.h) and of the numbers in them:
// nesting depth, size, repeated keys, NUL bytes, versions, parameter values and clip sizes.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <string>

#include "support/refusal.h"
#include "zeroset/error.h"
#include "zeroset/surface/clip.h"
#include "zeroset/surface/json_read.h"
#include "zeroset/surface/keyframes.h"
#include "zeroset/surface/scene.h"

namespace zeroset {
namespace {

using nlohmann::json;

using test::refusal;

std::string nested_arrays(int depth, const std::string& key = "junk") {
  return "{\"equation\": \"x^2+y^2+z^2-1\", \"" + key + "\": " + std::string(depth, '[') +
         std::string(depth, ']') + "}";
}

TEST(JsonLimits, DepthUpToTheLimitIsRead) {
  // The top object is level 1, so kMaxDepth - 1 arrays inside it reach the limit exactly.
  const json j = json_read::parse(nested_arrays(json_read::kMaxDepth - 1), "s.json");
  const json* at = &j["junk"];
  int depth = 1;
  while (at->is_array() && !at->empty()) at = &(*at)[0], ++depth;
  EXPECT_EQ(depth + 1, json_read::kMaxDepth);
}

TEST(JsonLimits, DeeperNestingIsRefusedWithItsPointer) {
  const std::string m =
      refusal([] { json_read::parse(nested_arrays(json_read::kMaxDepth), "s.json"); });
  std::string pointer = "/junk";
  for (int k = 0; k < json_read::kMaxDepth - 1; ++k) pointer += "/0";  // the 16th array
  EXPECT_NE(m.find("s.json: " + pointer + ": nested deeper than 16 levels"), std::string::npos)
      << m;
}

TEST(JsonLimits, HundredThousandLevelsAreRefusedWithoutRecursion) {
  // Deep enough that building (or copying, or destroying) the document recursively would
  // overflow the stack; it is refused at level 17 while parsing.
  const auto start = std::chrono::steady_clock::now();
  const std::string deep = nested_arrays(100'000);
  const std::string objects = "{\"k\": " + [] {
    std::string s;
    for (int k = 0; k < 100'000; ++k) s += "{\"a\":";
    s += "1";
    s += std::string(100'000, '}');
    return s;
  }() + "}";
  EXPECT_NE(refusal([&] { json_read::parse(deep, "d.json"); }).find("nested deeper"),
            std::string::npos);
  const std::string m = refusal([&] { json_read::parse(objects, "o.json"); });
  EXPECT_NE(m.find("o.json: /k/a/a/a/a/a/a/a/a/a/a/a/a/a/a/a: nested deeper"), std::string::npos)
      << m;
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
}

TEST(JsonLimits, RepeatedKeysAreRefusedWithTheirPointer) {
  EXPECT_NE(refusal([] {
              json_read::parse(R"({"a": 1, "a": 2})", "s.json");
            }).find("s.json: /a: duplicate key"),
            std::string::npos);
  const std::string m = refusal([] {
    json_read::parse(R"({"camera": {"fov_deg": 30, "x/y": [1, {"fov_deg": 1, "fov_deg": 2}]}})",
                     "s.json");
  });
  EXPECT_NE(m.find("s.json: /camera/x~1y/1/fov_deg: duplicate key"), std::string::npos) << m;
  // The same key in different objects is fine.
  EXPECT_NO_THROW(json_read::parse(R"({"a": {"b": 1}, "c": {"b": 2}})", "s.json"));
}

TEST(JsonLimits, NulBytesAreRefusedEvenAfterTheDocument) {
  std::string text = R"({"equation": "x^2+y^2+z^2-1"})";
  text += '\0';
  text += R"({"more": 1})";
  const std::string m = refusal([&] { json_read::parse(text, "s.json"); });
  EXPECT_NE(m.find("NUL byte at byte 29"), std::string::npos) << m;
}

TEST(JsonLimits, SyntaxErrorsAndHugeNumbersAreRefused) {
  EXPECT_NE(refusal([] { json_read::parse(R"({"a": 1,})", "s.json"); }).find("not valid JSON"),
            std::string::npos);
  EXPECT_NE(refusal([] { json_read::parse(R"({"a": 1e400})", "s.json"); }).find("not valid JSON"),
            std::string::npos);
  EXPECT_NE(
      refusal([] { json_read::parse(R"({"a": 1} {"b": 2})", "s.json"); }).find("not valid JSON"),
      std::string::npos);
}

TEST(JsonLimits, SizeIsCappedBeforeParsingAndBeforeReadingFurther) {
  const std::string big(json_read::kMaxBytes + 1, ' ');
  EXPECT_NE(refusal([&] { json_read::parse(big, "big.json"); }).find("more than a scene file"),
            std::string::npos);
  // An endless file: refused after kMaxBytes + a little, not read to the end.
  EXPECT_NE(refusal([] { json_read::read_file("/dev/zero"); }).find("larger than a scene file"),
            std::string::npos);
}

TEST(JsonLimits, UnknownVersionsAreRefused) {
  const auto read = [](const std::string& version) {
    return refusal([&] {
      scene_from_json(
          json::parse(R"({"equation": "x^2+y^2+z^2-1", "zeroset_scene": )" + version + "}"),
          "s.json");
    });
  };
  EXPECT_EQ(read("1"), "");
  for (const char* bad : {"2", "0", "1.5", "\"1\"", "null", "[1]"})
    EXPECT_NE(read(bad).find("s.json: /zeroset_scene: unknown scene format version"),
              std::string::npos)
        << bad;
}

TEST(JsonLimits, SavedScenesOfNestedKeysDoNotGrowFasterThanTheirText) {
  // Unknown top-level keys are kept for the viewer's save; saving and reading again keeps
  // them as they were, in text of about their own size at every depth.
  for (int depth : {4, 15}) {
    const std::string text = nested_arrays(depth, "kept");
    const Scene scene = scene_from_json(json_read::parse(text, "s.json"), "s.json");
    ASSERT_TRUE(scene.settings.contains("kept"));
    const std::string saved = scene_to_json(scene).dump(2);
    const Scene again = scene_from_json(json_read::parse(saved, "saved.json"), "saved.json");
    EXPECT_EQ(again.settings["kept"], scene.settings["kept"]);
    EXPECT_LT(saved.size(), 1000u + 4u * static_cast<std::size_t>(depth * depth)) << depth;
  }
}

TEST(JsonLimits, ParameterValuesAndRangeEndsObeyTheParameterLimit) {
  const auto read = [](const std::string& parameters) {
    return refusal([&] {
      scene_from_json(
          json::parse(R"({"equation": "x^2+y^2+z^2-a", "parameters": )" + parameters + "}"),
          "s.json");
    });
  };
  EXPECT_EQ(read(R"({"a": 1e100})"), "");
  EXPECT_NE(read(R"({"a": 1e101})").find("s.json: /parameters/a: "), std::string::npos);
  EXPECT_NE(read(R"({"a": {"value": -1e300}})").find("/parameters/a/value: "), std::string::npos);
  EXPECT_NE(read(R"({"a": {"min": -1e300, "max": 1}})").find("/parameters/a/min: "),
            std::string::npos);
  EXPECT_NE(read(R"({"a": {"min": 0, "max": 1.7e308}})").find("/parameters/a/max: "),
            std::string::npos);
  // Keyframes too, at their pointer.
  const Scene s =
      scene_from_json(json::parse(R"({"equation": "x^2+y^2+z^2-a", "parameters": {"a": 1},
                      "animation": {"keyframes": [{"time": 0, "params": {"a": 1e200}}]}})"),
                      "s.json");
  const std::string m = refusal([&] { read_keyframes(s.settings, s.surface, 10, "s.json"); });
  EXPECT_NE(m.find("s.json: /animation/keyframes/0/params/a: "), std::string::npos) << m;
}

TEST(JsonLimits, FittedRangesAlwaysHaveAFiniteSpan) {
  Surface s = surface_from_equation("x^2 + y^2 + z^2 - a - b - c");
  s.field.set_parameter("a", kMaxParameterMagnitude);
  s.field.set_parameter("b", -kMaxParameterMagnitude);
  s.ranges = {{"c", -1.7e308, 1.7e308}};  // not kept: its span is not finite
  s.fit_ranges();
  ASSERT_EQ(s.ranges.size(), 3u);
  for (const ParamSpec& r : s.ranges) {
    EXPECT_TRUE(std::isfinite(r.max - r.min)) << r.name;
    EXPECT_LT(r.min, r.max) << r.name;
  }
  EXPECT_EQ(s.ranges[2].min, -1.0);
}

TEST(ClipLimits, TinyAndHugeVolumesAreRefusedWithTheAllowedRange) {
  const auto add = [](const std::string& spec) {
    return refusal([&] {
      Clip c;
      c.add(spec);
      c.check_extent();
    });
  };
  EXPECT_NE(add("sphere:1e-300@1,0,0").find("at least 1e-06 times max(1"), std::string::npos);
  EXPECT_NE(add("sphere:1e-7@1e3,0,0").find("here 0.001"), std::string::npos);
  EXPECT_NE(add("sphere:1e100").find("range [-1e+07, 1e+07]"), std::string::npos);
  EXPECT_NE(add("sphere:1@0,0,2e7").find("range"), std::string::npos);
  EXPECT_NE(add("box:2e7").find("range"), std::string::npos);
  EXPECT_NE(add("box:0,0,0,1,1,1e-9").find("too small"), std::string::npos);
  EXPECT_NE(add("plane:0,0,1,1e300").find("range"), std::string::npos);
  EXPECT_EQ(add("sphere:1e-6"), "");
  EXPECT_EQ(add("sphere:1e7"), "");
  EXPECT_EQ(add("sphere:0.001@100,0,0"), "");
  // Tiny and huge normals are scaled before they are normalised.
  Clip c;
  c.add("plane:1e-300,0,0,1e-300");
  c.add("plane:-1e300,0,0,0");
  ASSERT_EQ(c.planes.size(), 2u);
  EXPECT_DOUBLE_EQ(c.planes[0].offset, 1.0);
  EXPECT_EQ(c.planes[0].normal, Vec3(1, 0, 0));
  EXPECT_EQ(c.planes[1].normal, Vec3(-1, 0, 0));
}

TEST(ClipLimits, EmptyOrSliveredVolumesAreRefusedAsAWhole) {
  Clip empty;
  empty.add("sphere:1");
  empty.add("plane:1,0,0,-2");
  EXPECT_NE(refusal([&] { empty.check_extent(); }).find("the clip volume is empty"),
            std::string::npos);
  Clip sliver;
  sliver.add("box:1");
  sliver.add("plane:0,0,1,-0.9999999999");
  EXPECT_NE(refusal([&] { sliver.check_extent(); }).find("too small"), std::string::npos);
  Clip open;  // oblique planes only: no bounded side to check
  open.add("plane:1,1,0,1");
  EXPECT_EQ(refusal([&] { open.check_extent(); }), "");
}

TEST(ClipLimits, SceneFilesReportClipLimitsAtTheirPointer) {
  const std::string m = refusal([] {
    scene_from_json(
        json::parse(R"({"equation": "x^2+y^2+z^2-1", "clip": ["sphere:2", "sphere:1e100"]})"),
        "s.json");
  });
  EXPECT_NE(m.find("s.json: /clip/1: "), std::string::npos) << m;
}

}  // namespace
}  // namespace zeroset
