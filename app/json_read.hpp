#pragma once
// Reading our own JSON back (report.json, the output of `eval`): the values are kept as a tree
// and looked up by key. The writer (shapematch/json.hpp) stores NaN and infinities as null.
#include <string>
#include <utility>
#include <vector>

namespace shapematch::app {

struct JsonNode {
  enum class Kind { Null, Bool, Number, String, Array, Object } kind = Kind::Null;
  double number = 0;
  std::string text;
  std::vector<std::pair<std::string, JsonNode>> members;  // object members; array items have no key

  // The member `key` of an object; nullptr when this is no object or has no such member.
  const JsonNode* get(const std::string& key) const;
  // The number at `key`; NaN when it is missing, null or not a number.
  double number_or_nan(const std::string& key) const;
};

// Throws InvalidInputError naming `path` where `text` is not valid JSON.
JsonNode parse_json(const std::string& text, const std::string& path);

// IoError when the file cannot be read.
JsonNode read_json_file(const std::string& path);

}  // namespace shapematch::app
