#include "readers/PlyReader.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <vector>

namespace stereo_fusion {
namespace {

enum class Format { kAscii, kBinaryLittle, kBinaryBig };
enum class ScalarType { kInt8, kUInt8, kInt16, kUInt16, kInt32, kUInt32, kFloat32, kFloat64 };

/// Accepts both the classic names (uchar, int, float) and the sized ones (uint8, int32, float32).
bool parseScalarType(const std::string& name, ScalarType* type) {
  static const std::pair<const char*, ScalarType> kNames[] = {
      {"char", ScalarType::kInt8},      {"int8", ScalarType::kInt8},
      {"uchar", ScalarType::kUInt8},    {"uint8", ScalarType::kUInt8},
      {"short", ScalarType::kInt16},    {"int16", ScalarType::kInt16},
      {"ushort", ScalarType::kUInt16},  {"uint16", ScalarType::kUInt16},
      {"int", ScalarType::kInt32},      {"int32", ScalarType::kInt32},
      {"uint", ScalarType::kUInt32},    {"uint32", ScalarType::kUInt32},
      {"float", ScalarType::kFloat32},  {"float32", ScalarType::kFloat32},
      {"double", ScalarType::kFloat64}, {"float64", ScalarType::kFloat64}};
  for (const auto& [text, value] : kNames) {
    if (name == text) {
      *type = value;
      return true;
    }
  }
  return false;
}

size_t byteSize(ScalarType type) {
  switch (type) {
    case ScalarType::kInt8:
    case ScalarType::kUInt8: return 1;
    case ScalarType::kInt16:
    case ScalarType::kUInt16: return 2;
    case ScalarType::kInt32:
    case ScalarType::kUInt32:
    case ScalarType::kFloat32: return 4;
    case ScalarType::kFloat64: return 8;
  }
  return 1;
}

bool isFloatType(ScalarType type) {
  return type == ScalarType::kFloat32 || type == ScalarType::kFloat64;
}

struct Property {
  std::string name;
  ScalarType type = ScalarType::kFloat32;  ///< value type (of the items, for a list)
  bool is_list = false;
  ScalarType count_type = ScalarType::kUInt8;  ///< list length type
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> properties;
};

struct Header {
  Format format = Format::kAscii;
  std::vector<Element> elements;
  size_t data_begin = 0;  ///< byte offset of the first element row
};

/// Reads the next line of the header starting at `*pos`; strips a trailing '\r'.
bool nextHeaderLine(const std::string& data, size_t* pos, std::string* line) {
  if (*pos >= data.size()) return false;
  const size_t end = data.find('\n', *pos);
  if (end == std::string::npos) return false;  // the header always ends with a newline
  *line = data.substr(*pos, end - *pos);
  if (!line->empty() && line->back() == '\r') line->pop_back();
  *pos = end + 1;
  return true;
}

bool parseHeader(const std::string& data, Header* header, std::string* error) {
  // A real header is a few hundred bytes; the cap keeps a huge garbage file from being scanned
  // line by line as if it were one.
  constexpr size_t kMaxHeaderBytes = 1 << 20;
  size_t pos = 0;
  std::string line;
  if (!nextHeaderLine(data, &pos, &line) || line != "ply") {
    *error = "not a PLY file (first line is not \"ply\")";
    return false;
  }
  bool have_format = false;
  int line_number = 1;
  while (true) {
    if (pos > kMaxHeaderBytes || !nextHeaderLine(data, &pos, &line)) {
      *error = "header has no end_header line";
      return false;
    }
    ++line_number;
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    const std::string where = "header line " + std::to_string(line_number) + " (\"" + line + "\")";
    if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "end_header") break;
    if (keyword == "format") {
      std::string format, version;
      words >> format >> version;
      if (format == "ascii") {
        header->format = Format::kAscii;
      } else if (format == "binary_little_endian") {
        header->format = Format::kBinaryLittle;
      } else if (format == "binary_big_endian") {
        header->format = Format::kBinaryBig;
      } else {
        *error = "unsupported format in " + where;
        return false;
      }
      have_format = true;
    } else if (keyword == "element") {
      Element element;
      std::string count_text;
      words >> element.name >> count_text;
      const char* first = count_text.data();
      const char* last = first + count_text.size();
      const auto [end, ec] = std::from_chars(first, last, element.count);
      if (element.name.empty() || count_text.empty() || ec != std::errc() || end != last) {
        *error = "malformed element in " + where;
        return false;
      }
      header->elements.push_back(std::move(element));
    } else if (keyword == "property") {
      if (header->elements.empty()) {
        *error = "property before any element in " + where;
        return false;
      }
      Property property;
      std::string type_name;
      words >> type_name;
      if (type_name == "list") {
        std::string count_type, item_type;
        words >> count_type >> item_type >> property.name;
        property.is_list = true;
        if (!parseScalarType(count_type, &property.count_type) ||
            !parseScalarType(item_type, &property.type) || isFloatType(property.count_type)) {
          *error = "unsupported list types in " + where;
          return false;
        }
      } else {
        words >> property.name;
        if (!parseScalarType(type_name, &property.type)) {
          *error = "unsupported property type in " + where;
          return false;
        }
      }
      if (property.name.empty()) {
        *error = "property without a name in " + where;
        return false;
      }
      header->elements.back().properties.push_back(std::move(property));
    } else {
      *error = "unknown keyword in " + where;
      return false;
    }
  }
  if (!have_format) {
    *error = "header has no format line";
    return false;
  }
  header->data_begin = pos;
  return true;
}

/// Reads scalar values one at a time from the body, in the file's encoding, never past `end`.
class ValueReader {
 public:
  ValueReader(const char* begin, const char* end, Format format)
      : pos_(begin), end_(end), format_(format) {
    const uint16_t probe = 1;
    uint8_t first_byte;
    std::memcpy(&first_byte, &probe, 1);
    const bool host_little = first_byte == 1;
    swap_ = format != Format::kAscii && host_little != (format == Format::kBinaryLittle);
  }

  /// Reads one value of `type` into `value`; false at the end of the data or on a token that
  /// is not a number of that kind.
  bool read(ScalarType type, double* value) {
    return format_ == Format::kAscii ? readAscii(type, value) : readBinary(type, value);
  }

  size_t remainingBytes() const { return static_cast<size_t>(end_ - pos_); }

 private:
  bool readBinary(ScalarType type, double* value) {
    const size_t size = byteSize(type);
    if (remainingBytes() < size) return false;
    unsigned char bytes[8];
    std::memcpy(bytes, pos_, size);
    pos_ += size;
    if (swap_) std::reverse(bytes, bytes + size);
    switch (type) {
      case ScalarType::kInt8: *value = static_cast<int8_t>(bytes[0]); break;
      case ScalarType::kUInt8: *value = bytes[0]; break;
      case ScalarType::kInt16: *value = load<int16_t>(bytes); break;
      case ScalarType::kUInt16: *value = load<uint16_t>(bytes); break;
      case ScalarType::kInt32: *value = load<int32_t>(bytes); break;
      case ScalarType::kUInt32: *value = load<uint32_t>(bytes); break;
      case ScalarType::kFloat32: *value = load<float>(bytes); break;
      case ScalarType::kFloat64: *value = load<double>(bytes); break;
    }
    return true;
  }

  bool readAscii(ScalarType type, double* value) {
    while (pos_ < end_ && std::isspace(static_cast<unsigned char>(*pos_))) ++pos_;
    const char* token_end = pos_;
    while (token_end < end_ && !std::isspace(static_cast<unsigned char>(*token_end))) ++token_end;
    if (token_end == pos_) return false;
    const auto [parsed_end, ec] = std::from_chars(pos_, token_end, *value);
    if (ec != std::errc() || parsed_end != token_end) return false;
    pos_ = token_end;
    // An integer property holding 2.5 is a malformed file, not something to round.
    return isFloatType(type) || *value == std::floor(*value);
  }

  template <typename T>
  static T load(const unsigned char* bytes) {
    T value;
    std::memcpy(&value, bytes, sizeof(T));
    return value;
  }

  const char* pos_;
  const char* end_;
  Format format_;
  bool swap_ = false;
};

/// Fewest bytes one row of `element` can take, so a declared count can be checked against the
/// file size before allocating.
size_t minRowBytes(const Element& element, Format format) {
  size_t bytes = 0;
  for (const Property& property : element.properties) {
    // ASCII: at least one character and one separator per value.
    bytes += format == Format::kAscii
                 ? 2
                 : byteSize(property.is_list ? property.count_type : property.type);
  }
  return bytes;
}

/// Reads and discards one list or scalar property value.
bool skipProperty(const Property& property, ValueReader* reader) {
  double value;
  if (!property.is_list) return reader->read(property.type, &value);
  double length;
  if (!reader->read(property.count_type, &length) || length < 0) return false;
  for (double i = 0; i < length; ++i) {
    if (!reader->read(property.type, &value)) return false;
  }
  return true;
}

int findScalar(const Element& element, const char* name) {
  for (size_t i = 0; i < element.properties.size(); ++i) {
    const Property& p = element.properties[i];
    if (!p.is_list && p.name == name) return static_cast<int>(i);
  }
  return -1;
}

uint8_t toColorByte(double value, ScalarType type) {
  // Float colours are conventionally in [0, 1]; integer colours in [0, 255].
  const double scaled = isFloatType(type) ? value * 255.0 : value;
  if (!(scaled > 0)) return 0;  // also NaN
  return static_cast<uint8_t>(std::min(255.0, std::round(scaled)));
}

bool readVertices(const Element& element, ValueReader* reader, TriangleMesh* mesh,
                  std::string* error) {
  const int x = findScalar(element, "x"), y = findScalar(element, "y"),
            z = findScalar(element, "z");
  if (x < 0 || y < 0 || z < 0) {
    *error = "vertex element lacks one of the properties x, y, z";
    return false;
  }
  const int nx = findScalar(element, "nx"), ny = findScalar(element, "ny"),
            nz = findScalar(element, "nz");
  const int red = findScalar(element, "red"), green = findScalar(element, "green"),
            blue = findScalar(element, "blue");
  const bool has_normals = nx >= 0 && ny >= 0 && nz >= 0;
  const bool has_colors = red >= 0 && green >= 0 && blue >= 0;

  const size_t count = static_cast<size_t>(element.count);
  mesh->positions.resize(count);
  if (has_normals) mesh->normals.resize(count);
  if (has_colors) mesh->colors.resize(count);
  std::vector<double> row(element.properties.size(), 0.0);
  for (size_t v = 0; v < count; ++v) {
    for (size_t p = 0; p < element.properties.size(); ++p) {
      const Property& property = element.properties[p];
      const bool ok =
          property.is_list ? skipProperty(property, reader) : reader->read(property.type, &row[p]);
      if (!ok) {
        *error =
            "truncated or malformed vertex " + std::to_string(v) + " of " + std::to_string(count);
        return false;
      }
    }
    const Eigen::Vector3d position(row[x], row[y], row[z]);
    if (!position.allFinite()) {
      *error = "vertex " + std::to_string(v) + " has a non-finite coordinate";
      return false;
    }
    mesh->positions[v] = position.cast<float>();
    if (has_normals) mesh->normals[v] = Eigen::Vector3d(row[nx], row[ny], row[nz]).cast<float>();
    if (has_colors) {
      mesh->colors[v] = {toColorByte(row[red], element.properties[red].type),
                         toColorByte(row[green], element.properties[green].type),
                         toColorByte(row[blue], element.properties[blue].type)};
    }
  }
  return true;
}

bool readFaces(const Element& element, uint64_t vertex_count, ValueReader* reader,
               TriangleMesh* mesh, std::string* error) {
  int indices = -1;
  for (size_t i = 0; i < element.properties.size(); ++i) {
    const Property& p = element.properties[i];
    if (p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index")) {
      indices = static_cast<int>(i);
    }
  }
  if (indices < 0) {
    *error = "face element has no list property vertex_indices";
    return false;
  }
  if (isFloatType(element.properties[indices].type)) {
    *error = "face vertex_indices must have an integer type";
    return false;
  }
  const size_t count = static_cast<size_t>(element.count);
  mesh->triangles.reserve(count);
  std::vector<uint32_t> corners;
  for (size_t f = 0; f < count; ++f) {
    const std::string where = "face " + std::to_string(f) + " of " + std::to_string(count);
    for (size_t p = 0; p < element.properties.size(); ++p) {
      const Property& property = element.properties[p];
      if (static_cast<int>(p) != indices) {
        if (!skipProperty(property, reader)) {
          *error = "truncated or malformed " + where;
          return false;
        }
        continue;
      }
      double length;
      if (!reader->read(property.count_type, &length) || length < 0 ||
          length > static_cast<double>(reader->remainingBytes())) {
        *error = "truncated or malformed " + where;
        return false;
      }
      corners.clear();
      for (double i = 0; i < length; ++i) {
        double index;
        if (!reader->read(property.type, &index)) {
          *error = "truncated or malformed " + where;
          return false;
        }
        if (index < 0 || index >= static_cast<double>(vertex_count)) {
          *error = where + " uses vertex " + std::to_string(static_cast<long long>(index)) +
                   ", but there are only " + std::to_string(vertex_count) + " vertices";
          return false;
        }
        corners.push_back(static_cast<uint32_t>(index));
      }
      // Fan triangulation: exact for the convex polygons PLY writers emit.
      for (size_t k = 1; k + 1 < corners.size(); ++k) {
        mesh->triangles.push_back({corners[0], corners[k], corners[k + 1]});
      }
    }
  }
  return true;
}

bool readFile(const std::string& path, std::string* data, std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = "cannot open (" + std::string(std::strerror(errno)) + ")";
    return false;
  }
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) {
    *error = "cannot read (not a regular file?)";
    return false;
  }
  in.seekg(0, std::ios::beg);
  data->resize(static_cast<size_t>(size));
  if (!in.read(data->data(), size)) {
    *error = "read failed";
    return false;
  }
  return true;
}

bool readPlyData(const std::string& data, TriangleMesh* mesh, std::string* error) {
  Header header;
  if (!parseHeader(data, &header, error)) return false;

  const Element* vertex_element = nullptr;
  const Element* face_element = nullptr;
  for (const Element& element : header.elements) {
    const Element** slot = element.name == "vertex" ? &vertex_element
                           : element.name == "face" ? &face_element
                                                    : nullptr;
    if (slot && *slot) {
      *error = "more than one element \"" + element.name + "\"";
      return false;
    }
    if (slot) *slot = &element;
  }
  if (!vertex_element) {
    *error = "no vertex element";
    return false;
  }
  if (vertex_element->count > std::numeric_limits<uint32_t>::max()) {
    *error = "too many vertices for 32-bit indices";
    return false;
  }

  ValueReader reader(data.data() + header.data_begin, data.data() + data.size(), header.format);
  for (const Element& element : header.elements) {
    // An element without properties has nothing to read, whatever count it declares.
    if (element.properties.empty()) continue;
    const size_t min_row = minRowBytes(element, header.format);
    // ASCII: the last value of the file may lack its trailing separator.
    const size_t available = reader.remainingBytes() + (header.format == Format::kAscii ? 1 : 0);
    if (element.count > available / min_row) {
      *error = "truncated: element \"" + element.name + "\" declares " +
               std::to_string(element.count) + " rows but only " +
               std::to_string(reader.remainingBytes()) + " bytes of data remain";
      return false;
    }
    bool ok = true;
    if (&element == vertex_element) {
      ok = readVertices(element, &reader, mesh, error);
    } else if (&element == face_element) {
      ok = readFaces(element, vertex_element->count, &reader, mesh, error);
    } else {
      for (uint64_t row = 0; ok && row < element.count; ++row) {
        for (const Property& property : element.properties) {
          if (!skipProperty(property, &reader)) {
            *error = "truncated or malformed element \"" + element.name + "\" row " +
                     std::to_string(row);
            ok = false;
            break;
          }
        }
      }
    }
    if (!ok) return false;
  }
  return true;
}

}  // namespace

bool readPly(const std::string& path, TriangleMesh* mesh, std::string* error) {
  mesh->clear();
  std::string data;
  std::string reason;
  if (!readFile(path, &data, &reason) || !readPlyData(data, mesh, &reason)) {
    mesh->clear();
    if (error) *error = path + ": " + reason;
    return false;
  }
  return true;
}

}  // namespace stereo_fusion
