#include "json_read.hpp"

#include "shapematch/errors.hpp"
#include "shapematch/files.hpp"

#include <cctype>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <string_view>

namespace shapematch::app {

const JsonNode* JsonNode::get(const std::string& key) const {
  if (kind != Kind::Object) return nullptr;
  for (const auto& [k, v] : members)
    if (k == key) return &v;
  return nullptr;
}

double JsonNode::number_or_nan(const std::string& key) const {
  const JsonNode* v = get(key);
  return v && v->kind == Kind::Number ? v->number : std::numeric_limits<double>::quiet_NaN();
}

namespace {

class JsonParser {
public:
  JsonParser(const std::string& text, const std::string& path) : text_(text), path_(path) {}

  JsonNode parse() {
    JsonNode root = value(0);
    skip_space();
    if (pos_ != text_.size()) fail("unexpected text after the JSON value");
    return root;
  }

private:
  [[noreturn]] void fail(const std::string& problem) const {
    throw InvalidInputError(path_ + ": not valid JSON at byte " + std::to_string(pos_) + ": " + problem);
  }
  void skip_space() {
    while (pos_ < text_.size() && std::string_view(" \t\r\n").find(text_[pos_]) != std::string_view::npos) ++pos_;
  }
  bool eat(char c) {
    skip_space();
    if (pos_ < text_.size() && text_[pos_] == c) return ++pos_, true;
    return false;
  }
  void expect(char c) {
    if (!eat(c)) fail(std::string("expected '") + c + "'");
  }

  JsonNode value(int depth) {
    if (depth > 64) fail("nested too deeply");
    skip_space();
    if (pos_ >= text_.size()) fail("unexpected end");
    JsonNode node;
    const char c = text_[pos_];
    if (c == '{' || c == '[') {
      const bool object = c == '{';
      node.kind = object ? JsonNode::Kind::Object : JsonNode::Kind::Array;
      ++pos_;
      if (eat(object ? '}' : ']')) return node;
      do {
        std::string key;
        if (object) {
          skip_space();
          key = string();
          expect(':');
        }
        node.members.emplace_back(std::move(key), value(depth + 1));
      } while (eat(','));
      expect(object ? '}' : ']');
    } else if (c == '"') {
      node.kind = JsonNode::Kind::String;
      node.text = string();
    } else if (literal("true")) {
      node.kind = JsonNode::Kind::Bool;
      node.number = 1;
    } else if (literal("false")) {
      node.kind = JsonNode::Kind::Bool;
    } else if (literal("null")) {
      node.kind = JsonNode::Kind::Null;
    } else {
      const size_t begin = pos_;
      while (pos_ < text_.size() && std::string_view("+-0123456789.eE").find(text_[pos_]) != std::string_view::npos)
        ++pos_;
      const std::string token = text_.substr(begin, pos_ - begin);
      char* end = nullptr;
      node.kind = JsonNode::Kind::Number;
      node.number = token.empty() ? 0 : std::strtod(token.c_str(), &end);
      if (token.empty() || end != token.c_str() + token.size()) fail("expected a value");
    }
    return node;
  }

  bool literal(const char* word) {
    const std::string_view w(word);
    if (text_.compare(pos_, w.size(), w) != 0) return false;
    pos_ += w.size();
    return true;
  }

  std::string string() {
    if (pos_ >= text_.size() || text_[pos_] != '"') fail("expected a string");
    ++pos_;
    std::string out;
    while (true) {
      if (pos_ >= text_.size()) fail("unterminated string");
      const char c = text_[pos_++];
      if (c == '"') return out;
      if (c != '\\') {
        out += c;
        continue;
      }
      if (pos_ >= text_.size()) fail("unterminated string");
      const char e = text_[pos_++];
      switch (e) {
        case '"': case '\\': case '/': out += e; break;
        case 'b': out += '\b'; break;
        case 'f': out += '\f'; break;
        case 'n': out += '\n'; break;
        case 'r': out += '\r'; break;
        case 't': out += '\t'; break;
        case 'u': {
          if (pos_ + 4 > text_.size()) fail("short \\u escape");
          unsigned code = 0;
          for (int i = 0; i < 4; ++i) {
            const unsigned char h = static_cast<unsigned char>(text_[pos_++]);
            if (!std::isxdigit(h)) fail("bad \\u escape");
            code = code * 16 + (std::isdigit(h) ? h - '0' : std::tolower(h) - 'a' + 10);
          }
          // UTF-8; the writer escapes only control characters, so surrogate pairs are not joined.
          if (code < 0x80) {
            out += static_cast<char>(code);
          } else if (code < 0x800) {
            out += static_cast<char>(0xC0 | (code >> 6));
            out += static_cast<char>(0x80 | (code & 0x3F));
          } else {
            out += static_cast<char>(0xE0 | (code >> 12));
            out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
            out += static_cast<char>(0x80 | (code & 0x3F));
          }
          break;
        }
        default: fail("bad escape");
      }
    }
  }

  const std::string& text_;
  const std::string& path_;
  size_t pos_ = 0;
};

}  // namespace

JsonNode parse_json(const std::string& text, const std::string& path) { return JsonParser(text, path).parse(); }

JsonNode read_json_file(const std::string& path) {
  std::ifstream in = open_for_reading(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return parse_json(s.str(), path);
}

}  // namespace shapematch::app
