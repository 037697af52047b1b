#pragma once
// A registry of the parameters of one configuration struct: per parameter its name, type, unit,
// accepted range and meaning (ParameterSpec), a setter that parses and range-checks its textual
// value and a getter that prints it. One definition per parameter serves validation, --set,
// YAML and ROS loading and the generated tables of doc/parameters.md. The mapping parameters
// (MapperConfig, src/MapperConfig.cpp) and the nodelet's own (NodeConfig,
// src/ros/RosParameters.cpp) are two tables of this kind. ROS-free.
#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace stereo_fusion {

/// Description of one parameter, for validation, --set, YAML loading and the tables in
/// doc/parameters.md.
struct ParameterSpec {
  std::string name;
  std::string type;   ///< "double", "int", "bool", "enum" or "string"
  std::string unit;   ///< "m", "px", "vox", "" ...
  std::string range;  ///< human-readable range, e.g. "[0.002, 1]" or "naive | accelerated"
  std::string description;
};

/// The text forms of the tables' values (shared by every table).
namespace parameter_text {
/// Shortest form that reads back as the same double (0.02, not 0.020000000000000000416).
std::string formatDouble(double v);
/// The whole text is one number (no spaces, no suffix); subnormals parse.
bool parseDouble(const std::string& text, double* out);
/// The whole text is one integer within int's range.
bool parseInt(const std::string& text, int* out);
/// Levenshtein distance: the fewest insertions, deletions and substitutions from a to b.
size_t editDistance(const std::string& a, const std::string& b);
/// The name of `known` nearest to `name` by editDistance (the first of equally near ones);
/// empty when `known` is.
std::string nearestName(const std::string& name, const std::vector<std::string>& known);
/// "unknown parameter 'shown' (did you mean 'nearest'?)", the nearest of `known` to `name`
/// (`shown` is the name as the user wrote it, e.g. with its ROS namespace).
std::string unknownParameterMessage(const std::string& shown, const std::string& name,
                                    const std::vector<std::string>& known);
}  // namespace parameter_text

template <typename Config>
class ParameterTable {
 public:
  /// Selects the field a parameter sets (a member, or a member of a member).
  template <typename T>
  using Field = std::function<T&(Config&)>;
  template <typename T>
  static Field<T> member(T Config::*m) {
    return [m](Config& c) -> T& { return c.*m; };
  }

  /// A double in (lo or [lo, hi]; NaN and infinities are refused.
  void addDouble(std::string name, std::string unit, double lo, bool lo_inclusive, double hi,
                 std::string description, Field<double> field) {
    using namespace parameter_text;
    const std::string range =
        (lo_inclusive ? "[" : "(") + formatDouble(lo) + ", " + formatDouble(hi) + "]";
    const std::string range_with_unit = withUnit(range, unit);
    Entry e;
    e.spec = {name, "double", std::move(unit), range, std::move(description)};
    e.set = [=](Config* c, const std::string& text, std::string* error) {
      double v = 0;
      if (!parseDouble(text, &v) || !std::isfinite(v)) {
        *error = "parameter '" + name + "': '" + text + "' is not a finite number";
        return false;
      }
      if ((lo_inclusive ? v < lo : v <= lo) || v > hi) {
        *error = "parameter '" + name + "' = " + text + " is out of range " + range_with_unit;
        return false;
      }
      field(*c) = v;
      return true;
    };
    e.get = [field](const Config& c) { return formatDouble(read(field, c)); };
    add(std::move(e));
  }

  /// An int in [lo, hi].
  void addInt(std::string name, std::string unit, int lo, int hi, std::string description,
              Field<int> field) {
    using namespace parameter_text;
    const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    const std::string range_with_unit = withUnit(range, unit);
    Entry e;
    e.spec = {name, "int", std::move(unit), range, std::move(description)};
    e.set = [=](Config* c, const std::string& text, std::string* error) {
      int v = 0;
      if (!parseInt(text, &v)) {
        *error = "parameter '" + name + "': '" + text + "' is not an integer";
        return false;
      }
      if (v < lo || v > hi) {
        *error = "parameter '" + name + "' = " + text + " is out of range " + range_with_unit;
        return false;
      }
      field(*c) = v;
      return true;
    };
    e.get = [field](const Config& c) { return std::to_string(read(field, c)); };
    add(std::move(e));
  }

  /// One of the labels in `values` (the first label of a value is the one printed).
  template <typename Enum>
  void addEnum(std::string name, std::vector<std::pair<std::string, Enum>> values,
               std::string description, Field<Enum> field) {
    std::string range;
    for (const auto& [label, value] : values) range += (range.empty() ? "" : " | ") + label;
    Entry e;
    e.spec = {name, "enum", "", range, std::move(description)};
    e.set = [=](Config* c, const std::string& text, std::string* error) {
      for (const auto& [label, value] : values) {
        if (label == text) {
          field(*c) = value;
          return true;
        }
      }
      *error = "parameter '" + name + "': '" + text + "' is not one of " + range;
      return false;
    };
    e.get = [=](const Config& c) {
      for (const auto& [label, value] : values)
        if (value == read(field, c)) return label;
      return std::string();
    };
    add(std::move(e));
  }

  /// true / false (also 1 / 0).
  void addBool(std::string name, std::string description, Field<bool> field) {
    Entry e;
    e.spec = {name, "bool", "", "true | false", std::move(description)};
    e.set = [=](Config* c, const std::string& text, std::string* error) {
      if (text == "true" || text == "1") {
        field(*c) = true;
      } else if (text == "false" || text == "0") {
        field(*c) = false;
      } else {
        *error = "parameter '" + name + "': '" + text + "' is not true or false";
        return false;
      }
      return true;
    };
    e.get = [field](const Config& c) { return std::string(read(field, c) ? "true" : "false"); };
    add(std::move(e));
  }

  /// Any text; with `allow_empty` = false not the empty one. `range` describes what is accepted.
  void addString(std::string name, bool allow_empty, std::string range, std::string description,
                 Field<std::string> field) {
    Entry e;
    e.spec = {name, "string", "", range, std::move(description)};
    e.set = [=](Config* c, const std::string& text, std::string* error) {
      if (!allow_empty && text.empty()) {
        *error = "parameter '" + name + "' must not be empty (" + range + ")";
        return false;
      }
      field(*c) = text;
      return true;
    };
    e.get = [field](const Config& c) { return read(field, c); };
    add(std::move(e));
  }

  /// Every parameter, in the order they were added.
  const std::vector<ParameterSpec>& specs() const { return specs_; }

  /// Sets parameter `name` from its textual value. False with a message naming the parameter
  /// (and its range and unit; an unknown name with the nearest known one) when the name is unknown,
  /// the value does not parse or is out of range; *config is then unchanged.
  bool set(Config* config, const std::string& name, const std::string& value,
           std::string* error) const {
    const Entry* e = find(name);
    if (e == nullptr) {
      std::vector<std::string> known;
      for (const ParameterSpec& spec : specs_) known.push_back(spec.name);
      *error = parameter_text::unknownParameterMessage(name, name, known);
      return false;
    }
    return e->set(config, value, error);
  }

  /// Textual value of parameter `name` (as set() accepts it); empty if unknown.
  std::string get(const Config& config, const std::string& name) const {
    const Entry* e = find(name);
    return e ? e->get(config) : std::string();
  }

  /// One message per value that its setter would refuse (range, emptiness), in table order.
  std::vector<std::string> rangeErrors(const Config& config) const {
    std::vector<std::string> errors;
    for (const Entry& e : entries_) {
      Config scratch;
      std::string error;
      if (!e.set(&scratch, e.get(config), &error)) errors.push_back(error);
    }
    return errors;
  }

 private:
  struct Entry {
    ParameterSpec spec;
    std::function<bool(Config*, const std::string&, std::string*)> set;
    std::function<std::string(const Config&)> get;
  };

  template <typename T>
  static const T& read(const Field<T>& field, const Config& c) {
    return field(const_cast<Config&>(c));  // the field lambdas only select, never write
  }
  static std::string withUnit(const std::string& range, const std::string& unit) {
    return unit.empty() ? range : range + " " + unit;
  }
  void add(Entry e) {
    if (find(e.spec.name) != nullptr)
      throw std::logic_error("parameter '" + e.spec.name + "' is defined twice");
    specs_.push_back(e.spec);
    entries_.push_back(std::move(e));
  }
  const Entry* find(const std::string& name) const {
    for (const Entry& e : entries_)
      if (e.spec.name == name) return &e;
    return nullptr;
  }

  std::vector<Entry> entries_;
  std::vector<ParameterSpec> specs_;
};

}  // namespace stereo_fusion
