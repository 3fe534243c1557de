#include "common/json_parse.h"

#include <gtest/gtest.h>

#include <string>

namespace vobb {
namespace {

std::string nested(int depth) { return std::string(depth + 1, '[') + std::string(depth + 1, ']'); }

// The top level is depth 0: "[]" is depth 0, "[[]]" depth 1. A document at the limit is read
// whole; one level more is refused, for objects as for arrays.
TEST(JsonParse, NestingUpToTheLimitIsReadAndBeyondIsRefused) {
  nlohmann::json j;
  EXPECT_TRUE(parse_json_within(nested(3), 3, &j));
  EXPECT_EQ(j.dump(), nested(3));
  EXPECT_FALSE(parse_json_within(nested(4), 3, &j));
  EXPECT_TRUE(parse_json_within(R"({"a":{"b":{"c":{}}}})", 3, &j));
  EXPECT_FALSE(parse_json_within(R"({"a":{"b":{"c":{"d":{}}}}})", 3, &j));
  nlohmann::ordered_json o;
  EXPECT_TRUE(parse_json_within(R"({"z":1,"a":[1,2]})", 1, &o));
  EXPECT_EQ(o.dump(), R"({"z":1,"a":[1,2]})") << "the caller's JSON type, with its key order";
}

TEST(JsonParse, NotJsonIsRefused) {
  nlohmann::json j;
  bool too_deep = true;
  EXPECT_FALSE(parse_json_within("", 8, &j, &too_deep));
  EXPECT_FALSE(too_deep) << "not JSON, which is not the same refusal";
  EXPECT_FALSE(parse_json_within("{\"a\":", 8, &j));
  EXPECT_FALSE(parse_json_within("[1,]", 8, &j));
  EXPECT_TRUE(parse_json_within("5", 0, &j));
}

// A key twice in one object is refused, whichever object, and the key is named; the same key
// in different objects, or in an object and one nested in it, is not a repeat.
TEST(JsonParse, AKeyTwiceInOneObjectIsRefused) {
  nlohmann::json j;
  bool too_deep = true;
  std::string twice;
  EXPECT_FALSE(parse_json_within(R"({"depth":7,"a":1,"depth":2})", 8, &j, &too_deep, &twice));
  EXPECT_EQ(twice, "depth");
  EXPECT_FALSE(too_deep);
  EXPECT_TRUE(j.is_null()) << "reset";
  EXPECT_EQ(json_refusal(too_deep, twice, "a tree file"), "the key \"depth\" twice in one object");
  EXPECT_FALSE(
      parse_json_within(R"({"n":[{"x":1},{"x":2,"y":[],"x":3}]})", 8, &j, &too_deep, &twice));
  EXPECT_EQ(twice, "x");
  EXPECT_TRUE(
      parse_json_within(R"({"x":{"x":{"x":1}},"n":[{"x":1},{"x":2}]})", 8, &j, &too_deep, &twice));
  EXPECT_TRUE(twice.empty());
  EXPECT_EQ(j["n"][1]["x"], 2);
  // A long or odd key stays on one line in the refusal.
  const std::string odd = std::string(100, 'k') + "\n";
  EXPECT_FALSE(parse_json_within(
      "{\"" + std::string(100, 'k') + "\\n\":1,\"" + std::string(100, 'k') + "\\n\":2}", 8, &j,
      &too_deep, &twice));
  EXPECT_EQ(twice, odd);
  const std::string why = json_refusal(false, twice, "a box file");
  EXPECT_EQ(why.find('\n'), std::string::npos) << why;
  EXPECT_LT(why.size(), 100u) << why;
}

// Nested 10^6 deep: refused as too deep, with *out reset, so copying and writing it out (which
// recurse once per level) are safe. Unlimited, the copy would overflow the stack.
TEST(JsonParse, VeryDeepDocumentIsRefusedWithoutDeepRecursion) {
  nlohmann::json j = {{"stale", 1}};
  bool too_deep = false;
  EXPECT_FALSE(parse_json_within(R"({"x":)" + nested(1000000) + "}", 8, &j, &too_deep));
  EXPECT_TRUE(too_deep);
  const nlohmann::json copy = j;
  EXPECT_EQ(copy.dump(), "null");
}

// An array of 200,000 objects, as a tree of that many nodes would be: accepted, whole. (The
// callback parser that could also cut depth takes time quadratic in such an array.)
TEST(JsonParse, LongArrayOfObjectsIsReadWhole) {
  std::string text = "[";
  for (int i = 0; i < 200000; ++i)
    text += (i ? ",{\"a\":[" : "{\"a\":[") + std::to_string(i) + "]}";
  text += "]";
  nlohmann::json j;
  ASSERT_TRUE(parse_json_within(text, 2, &j));
  ASSERT_EQ(j.size(), 200000u);
  EXPECT_EQ(j[199999]["a"][0], 199999);
}

}  // namespace
}  // namespace vobb
