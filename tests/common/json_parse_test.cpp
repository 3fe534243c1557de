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
  EXPECT_FALSE(parse_json_within("", 8, &j));
  EXPECT_FALSE(parse_json_within("{\"a\":", 8, &j));
  EXPECT_FALSE(parse_json_within("[1,]", 8, &j));
  EXPECT_TRUE(parse_json_within("5", 0, &j));
}

// Nested 10^6 deep: refused, and what is kept is shallow, so copying and writing it out (which
// recurse once per level) are safe. Unlimited, the copy would overflow the stack.
TEST(JsonParse, VeryDeepDocumentIsRefusedWithoutDeepRecursion) {
  nlohmann::json j;
  EXPECT_FALSE(parse_json_within(R"({"x":)" + nested(1000000) + "}", 8, &j));
  const nlohmann::json copy = j;
  EXPECT_LT(copy.dump().size(), 100u);
}

}  // namespace
}  // namespace vobb
