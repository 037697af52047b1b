#pragma once
// Minimal JSON object builder for the evaluator's report (no dependency for a flat document).

#include <cstdint>
#include <string>
#include <vector>

namespace stereo_fusion::eval {

/// An ordered JSON object. Keys keep insertion order, so reports diff cleanly.
/// Non-finite numbers are written as null (JSON has no NaN or infinity).
class JsonObject {
 public:
  /// Adds a number (9 significant digits; null when not finite). Each adder returns *this.
  JsonObject& number(const std::string& key, double value);
  /// Adds an exact unsigned integer (counts).
  JsonObject& integer(const std::string& key, uint64_t value);
  /// Adds an escaped string.
  JsonObject& text(const std::string& key, const std::string& value);
  /// Adds true / false.
  JsonObject& boolean(const std::string& key, bool value);
  /// Adds a nested object, indented.
  JsonObject& object(const std::string& key, const JsonObject& value);
  /// Adds an array of objects, one object per line.
  JsonObject& array(const std::string& key, const std::vector<JsonObject>& values);
  /// Adds an array of integers on one line.
  JsonObject& integers(const std::string& key, const std::vector<size_t>& values);
  /// The document, indented by two spaces per level, without a trailing newline.
  std::string str(int indent = 0) const;

 private:
  struct Member {
    std::string key;
    std::string value;       ///< serialised JSON
    bool multiline = false;  ///< a nested document whose continuation lines need indenting
  };
  void add(const std::string& key, std::string value, bool multiline = false);

  std::vector<Member> members_;
};

/// `text` as a quoted JSON string with escapes.
std::string jsonQuote(const std::string& text);

}  // namespace stereo_fusion::eval
