#include "evaluator/JsonWriter.h"

#include <cmath>
#include <cstdio>

namespace stereo_fusion::eval {

std::string jsonQuote(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      case '\r': out += "\\r"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char escaped[8];
          std::snprintf(escaped, sizeof(escaped), "\\u%04x", c);
          out += escaped;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

void JsonObject::add(const std::string& key, std::string value, bool multiline) {
  members_.push_back({key, std::move(value), multiline});
}

JsonObject& JsonObject::number(const std::string& key, double value) {
  if (!std::isfinite(value)) {
    add(key, "null");
    return *this;
  }
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.9g", value);  // 9 digits: 1 nm at 1 km
  add(key, buffer);
  return *this;
}

JsonObject& JsonObject::integer(const std::string& key, uint64_t value) {
  add(key, std::to_string(value));
  return *this;
}

JsonObject& JsonObject::text(const std::string& key, const std::string& value) {
  add(key, jsonQuote(value));
  return *this;
}

JsonObject& JsonObject::boolean(const std::string& key, bool value) {
  add(key, value ? "true" : "false");
  return *this;
}

JsonObject& JsonObject::object(const std::string& key, const JsonObject& value) {
  add(key, value.str(0), true);
  return *this;
}

JsonObject& JsonObject::array(const std::string& key, const std::vector<JsonObject>& values) {
  // One item per line, each on a single line: per-frame rows stay readable and greppable.
  std::string out = "[";
  for (size_t i = 0; i < values.size(); ++i) out += (i ? ",\n  " : "\n  ") + values[i].str(-1);
  out += values.empty() ? "]" : "\n]";
  add(key, out, true);
  return *this;
}

JsonObject& JsonObject::integers(const std::string& key, const std::vector<size_t>& values) {
  std::string out = "[";
  for (size_t i = 0; i < values.size(); ++i) out += (i ? ", " : "") + std::to_string(values[i]);
  add(key, out + "]");
  return *this;
}

std::string JsonObject::str(int indent) const {
  if (indent < 0) {  // single line (nested documents are flattened: strings hold no raw newline)
    std::string out = "{";
    for (size_t i = 0; i < members_.size(); ++i) {
      std::string value = members_[i].value;
      for (char& c : value) {
        if (c == '\n') c = ' ';
      }
      out += (i ? ", " : "") + jsonQuote(members_[i].key) + ": " + value;
    }
    return out + "}";
  }
  const std::string pad(2 * (indent + 1), ' ');
  std::string out = "{\n";
  for (size_t i = 0; i < members_.size(); ++i) {
    std::string value;
    for (const char c : members_[i].value) {
      value += c;
      if (c == '\n' && members_[i].multiline) value += pad;
    }
    out += pad + jsonQuote(members_[i].key) + ": " + value +
           (i + 1 < members_.size() ? ",\n" : "\n");
  }
  return out + std::string(2 * indent, ' ') + "}";
}

}  // namespace stereo_fusion::eval
