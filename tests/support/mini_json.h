// A small strict JSON parser for tests that check the command line's reports by structure
// (nesting, array lengths, value types) rather than by substring. Throws std::runtime_error
// saying where the text stops being JSON.
#pragma once

#include <cctype>
#include <cstdlib>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace csculpt::test {

struct Json {
  enum class Type { null, boolean, number, string, array, object };
  Type type = Type::null;
  bool boolean = false;
  double number = 0;
  std::string string;
  std::vector<Json> array;
  std::map<std::string, Json> object;

  bool has(const std::string& key) const { return object.count(key) > 0; }
  /// The member `key`; throws when this is not an object holding it.
  const Json& operator[](const std::string& key) const {
    const auto it = object.find(key);
    if (type != Type::object || it == object.end())
      throw std::runtime_error("no member \"" + key + "\"");
    return it->second;
  }
  const Json& operator[](std::size_t i) const { return array.at(i); }
  std::size_t size() const { return type == Type::array ? array.size() : object.size(); }
};

class JsonParser {
 public:
  /// The one value `text` holds (surrounding white space allowed, nothing else).
  static Json parse(const std::string& text) {
    JsonParser p(text);
    Json v = p.value();
    p.space();
    if (p.at_ != text.size()) p.fail("text after the value");
    return v;
  }

 private:
  explicit JsonParser(const std::string& text) : s_(text) {}

  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error("JSON: " + what + " at offset " + std::to_string(at_));
  }
  void space() {
    while (at_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[at_]))) ++at_;
  }
  char peek() {
    space();
    if (at_ >= s_.size()) fail("unexpected end");
    return s_[at_];
  }
  void expect(char c) {
    if (peek() != c) fail(std::string("expected '") + c + "'");
    ++at_;
  }
  /// Consumes `c` if it comes next.
  bool closes(char c) {
    if (peek() != c) return false;
    ++at_;
    return true;
  }
  bool literal(const std::string& word) {
    if (s_.compare(at_, word.size(), word) != 0) return false;
    at_ += word.size();
    return true;
  }

  Json value() {
    const char c = peek();
    if (c == '{') return object();
    if (c == '[') return array();
    Json v;
    if (c == '"') {
      v.type = Json::Type::string;
      v.string = string();
    } else if (literal("true")) {
      v.type = Json::Type::boolean;
      v.boolean = true;
    } else if (literal("false")) {
      v.type = Json::Type::boolean;
    } else if (literal("null")) {
      v.type = Json::Type::null;
    } else {
      v.type = Json::Type::number;
      v.number = number();
    }
    return v;
  }
  Json object() {
    Json v;
    v.type = Json::Type::object;
    expect('{');
    if (closes('}')) return v;
    while (true) {
      if (peek() != '"') fail("expected a member name");
      std::string key = string();
      expect(':');
      v.object[key] = value();
      if (closes('}')) return v;
      expect(',');
    }
  }
  Json array() {
    Json v;
    v.type = Json::Type::array;
    expect('[');
    if (closes(']')) return v;
    while (true) {
      v.array.push_back(value());
      if (closes(']')) return v;
      expect(',');
    }
  }
  std::string string() {
    expect('"');
    std::string out;
    while (at_ < s_.size() && s_[at_] != '"') {
      char c = s_[at_++];
      if (static_cast<unsigned char>(c) < 0x20) fail("control character in a string");
      if (c == '\\') {
        if (at_ >= s_.size()) fail("unexpected end");
        c = s_[at_++];
        if (c == 'u') {  // tests only need to skip these
          at_ += 4;
          c = '?';
        } else if (c == 'n') {
          c = '\n';
        } else if (c == 't') {
          c = '\t';
        }
      }
      out += c;
    }
    if (at_ >= s_.size()) fail("unterminated string");
    ++at_;
    return out;
  }
  double number() {
    const char* start = s_.c_str() + at_;
    const char c = *start;
    if (!(c == '-' || std::isdigit(static_cast<unsigned char>(c)))) fail("expected a value");
    char* end = nullptr;
    const double v = std::strtod(start, &end);
    // strtod also reads nan, inf and hex, which JSON does not have
    for (const char* p = start; p < end; ++p)
      if (!(std::isdigit(static_cast<unsigned char>(*p)) || *p == '-' || *p == '+' || *p == '.' ||
            *p == 'e' || *p == 'E'))
        fail("not a JSON number");
    at_ += static_cast<std::size_t>(end - start);
    return v;
  }

  const std::string& s_;
  std::size_t at_ = 0;
};

}  // namespace csculpt::test
