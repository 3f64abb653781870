#include "selfsense/io/yaml_map.hpp"

#include <gtest/gtest.h>

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace selfsense::io {
namespace {

std::string error_of(const auto& action) {
  try {
    action();
  } catch (const YamlError& e) {
    return e.what();
  }
  return "no error";
}

TEST(YamlMap, TypedGettersRequiredOptionalAndDefaults) {
  YamlMap root = YamlMap::from_string("a: 1.5\nb: 3\nc: true\nd: text\n", "C.yaml");
  EXPECT_DOUBLE_EQ(root.required<double>("a"), 1.5);
  EXPECT_EQ(root.optional<int>("b", 7), 3);
  EXPECT_EQ(root.optional<int>("missing", 7), 7);
  bool c = false;
  root.read("c", c);
  EXPECT_TRUE(c);
  std::string d{"default"};
  root.read("d", d);
  EXPECT_EQ(d, "text");
  EXPECT_NO_THROW(root.finish());
}

TEST(YamlMap, MissingRequiredKeyNamesThePath) {
  YamlMap root = YamlMap::from_string("outer:\n  x: 1\n", "C.yaml");
  YamlMap outer = root.map("outer");
  EXPECT_EQ(error_of([&] { static_cast<void>(outer.required<double>("y")); }),
            "C.yaml:2: outer.y: required key is missing");
}

TEST(YamlMap, UnknownKeysAreErrorsWithLine) {
  YamlMap root = YamlMap::from_string("outer:\n  x: 1\n  typo: 2\n", "C.yaml");
  YamlMap outer = root.map("outer");
  static_cast<void>(outer.required<int>("x"));
  EXPECT_EQ(error_of([&] { outer.finish(); }), "C.yaml:3: outer.typo: unknown key");
  EXPECT_NO_THROW(root.finish());
}

TEST(YamlMap, DuplicateKeysAreErrors) {
  YamlMap root = YamlMap::from_string("x: 1\nx: 2\n", "C.yaml");
  static_cast<void>(root.required<int>("x"));
  EXPECT_EQ(error_of([&] { root.finish(); }), "C.yaml:2: x: duplicate key");
}

TEST(YamlMap, WrongTypesNameTheKey) {
  YamlMap root = YamlMap::from_string("n: abc\ni: 2.5\nb: maybe\nu: -3\nm: {a: 1}\n", "C.yaml");
  EXPECT_EQ(error_of([&] { static_cast<void>(root.required<double>("n")); }),
            "C.yaml:1: n: expected a number, got 'abc'");
  EXPECT_EQ(error_of([&] { static_cast<void>(root.required<int>("i")); }),
            "C.yaml:2: i: expected an integer, got '2.5'");
  EXPECT_EQ(error_of([&] { static_cast<void>(root.required<bool>("b")); }),
            "C.yaml:3: b: expected true or false, got 'maybe'");
  EXPECT_EQ(error_of([&] { static_cast<void>(root.required<std::uint64_t>("u")); }),
            "C.yaml:4: u: expected a non-negative integer, got '-3'");
  EXPECT_EQ(error_of([&] { static_cast<void>(root.required<double>("m")); }),
            "C.yaml:5: m: expected a number, got a mapping");
}

// Counts are std::size_t, which is unsigned int on 32-bit targets (armhf) and std::uint64_t on
// 64-bit ones: both read, and the narrow one refuses what it cannot hold.
TEST(YamlMap, CountsReadAsSizeOnEveryTargetAndUnsignedIntRefusesWhatItCannotHold) {
  YamlMap root =
      YamlMap::from_string("sizes: [3, 4294967295]\nn: 7\nbig: 4294967296\nneg: -1\n", "C.yaml");
  std::vector<std::size_t> sizes{};
  root.read_sequence("sizes", sizes);
  EXPECT_EQ(sizes, (std::vector<std::size_t>{3U, 4294967295U}));
  EXPECT_EQ(root.required<unsigned int>("n"), 7U);
  EXPECT_EQ(error_of([&] { static_cast<void>(root.required<unsigned int>("big")); }),
            "C.yaml:3: big: expected a non-negative integer up to 4294967295, got '4294967296'");
  EXPECT_EQ(error_of([&] { static_cast<void>(root.required<unsigned int>("neg")); }),
            "C.yaml:4: neg: expected a non-negative integer, got '-1'");
}

TEST(YamlMap, SequencesNameTheirElements) {
  YamlMap root = YamlMap::from_string("tau_s: [1, 2, x]\nok: [1, 2]\nscalar: 3\n", "C.yaml");
  std::vector<double> v{};
  EXPECT_EQ(error_of([&] { root.read_sequence("tau_s", v); }),
            "C.yaml:1: tau_s[2]: expected a number, got 'x'");
  root.read_sequence("ok", v);
  EXPECT_EQ(v, (std::vector<double>{1.0, 2.0}));
  EXPECT_EQ(error_of([&] { root.read_sequence("scalar", v); }),
            "C.yaml:3: scalar: expected a sequence");
}

TEST(YamlMap, SequencesOfMapsCarryIndexedPaths) {
  YamlMap root = YamlMap::from_string("items:\n  - {a: 1}\n  - {a: 2, b: 3}\n", "C.yaml");
  std::vector<YamlMap> items = root.maps("items");
  ASSERT_EQ(items.size(), 2U);
  EXPECT_EQ(items[1].path("b"), "items[1].b");
  static_cast<void>(items[1].required<int>("a"));
  EXPECT_EQ(error_of([&] { items[1].finish(); }), "C.yaml:3: items[1].b: unknown key");
}

TEST(YamlMap, LocateAddsTheLineOfAKeyReadEarlier) {
  YamlMap root = YamlMap::from_string("plant:\n  x: 1\n  y:\n    z: 5\n", "C.yaml");
  YamlMap plant = root.map("plant");
  YamlMap y = plant.map("y");
  static_cast<void>(y.required<int>("z"));
  EXPECT_EQ(root.locate("plant.y.z: 5: too large"), "C.yaml:4: plant.y.z: 5: too large");
  EXPECT_EQ(root.locate("other: bad"), "C.yaml:1: other: bad");
}

// Found by fuzzing (tests/fuzz/corpus/daemon_config/regression-default-*): a problem with a key
// left at its default named no line, against check-config's `FILE:LINE: KEY.PATH: what`.
TEST(YamlMap, LocateGivesADefaultKeyTheLineOfTheKeyItConflictsWith) {
  YamlMap root = YamlMap::from_string("a: 1\ncontrol:\n  range: [1, 2]\n", "C.yaml");
  YamlMap control = root.map("control");
  std::vector<double> range;
  control.read_sequence("range", range);
  EXPECT_EQ(root.locate("safety.value: must be inside control.range"),
            "C.yaml:3: safety.value: must be inside control.range");
  // The section, when the key itself is not in the file either; else the document.
  EXPECT_EQ(root.locate("safety.value: must be inside control.ranges"),
            "C.yaml:2: safety.value: must be inside control.ranges");
  EXPECT_EQ(root.locate("safety.value: must be positive"),
            "C.yaml:1: safety.value: must be positive");
}

TEST(YamlMap, ParseErrorsAndNonMappingDocuments) {
  EXPECT_NE(error_of([] {
              static_cast<void>(YamlMap::from_string("a: [1, 2\n", "C.yaml"));
            }).find("C.yaml:"),
            std::string::npos);
  EXPECT_EQ(error_of([] { static_cast<void>(YamlMap::from_string("- 1\n", "C.yaml")); }),
            "C.yaml:1: the document must be a mapping of keys to values");
  EXPECT_EQ(error_of([] { static_cast<void>(YamlMap::load_file("/nonexistent/x.yaml")); }),
            "/nonexistent/x.yaml: cannot open the file");
}

// Found by fuzzing (tests/fuzz/corpus/daemon_config/regression-plant-is-a-directory.yaml): a
// path that names a directory reached yaml-cpp, which leaked its stream buffer; a file that
// cannot be read is named as such.
TEST(YamlMap, ADirectoryOrAnUnreadableFileIsNamed) {
  const std::filesystem::path directory = std::filesystem::temp_directory_path();
  EXPECT_EQ(error_of([&] { static_cast<void>(YamlMap::load_file(directory)); }),
            directory.string() + ": not a regular file");
  const std::filesystem::path file = directory / "selfsense-yaml-map-test.yaml";
  {
    std::ofstream out{file};
    out << "a: 1\n";
  }
  YamlMap root = YamlMap::load_file(file);
  EXPECT_EQ(root.required<int>("a"), 1);
  EXPECT_EQ(root.locate("a: x"), file.string() + ":1: a: x");
  std::filesystem::remove(file);
}

// Found by fuzzing (tests/fuzz/corpus/daemon_config/regression-*): a YAML escape, a quoted
// value or a key with a line break made a problem of two lines out of one.
TEST(YamlMap, EveryErrorIsOneLine) {
  // yaml-cpp names an unknown escape by its raw byte.
  EXPECT_EQ(error_of([] { static_cast<void>(YamlMap::from_string("a: \"x\\\x1d\"\n", "C.yaml")); }),
            "C.yaml:1: unknown escape character: \\x1d");
  EXPECT_EQ(error_of([] {
              YamlMap root = YamlMap::from_string("n: \"1\\n2\\t\\e\"\n", "C.yaml");
              static_cast<void>(root.required<int>("n"));
            }),
            "C.yaml:1: n: expected an integer, got '1\\n2\\t\\x1b'");
  EXPECT_EQ(error_of([] {
              YamlMap root = YamlMap::from_string("\"bad\\nkey\": 1\n", "C.yaml");
              root.finish();
            }),
            "C.yaml:1: bad\\nkey: unknown key");
  YamlMap root = YamlMap::from_string("a: 1\n", "C.yaml");
  EXPECT_EQ(root.locate("driver.type: 'x\ny' is not a type"),
            "C.yaml:1: driver.type: 'x\\ny' is not a type");
  const std::string long_value(100, 'v');
  EXPECT_EQ(error_of([&] {
              YamlMap map = YamlMap::from_string("n: " + long_value + "\n", "C.yaml");
              static_cast<void>(map.required<int>("n"));
            }),
            "C.yaml:1: n: expected an integer, got '" + long_value.substr(0, 64) + "...'");
}

}  // namespace
}  // namespace selfsense::io
