#include "docs/MarkdownLinks.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

namespace stereo_fusion {
namespace {

namespace fs = std::filesystem;

bool readText(const fs::path& path, std::string* text) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream s;
  s << in.rdbuf();
  *text = s.str();
  return true;
}

bool isFence(const std::string& line) {
  const size_t first = line.find_first_not_of(' ');
  return first != std::string::npos && first <= 3 &&
         (line.compare(first, 3, "```") == 0 || line.compare(first, 3, "~~~") == 0);
}

/// Calls f(line, number) for every line outside code fences.
template <typename F>
void forEachProseLine(const std::string& text, F&& f) {
  std::istringstream lines(text);
  std::string line;
  bool in_fence = false;
  for (int number = 1; std::getline(lines, line); ++number) {
    if (isFence(line)) {
      in_fence = !in_fence;
      continue;
    }
    if (!in_fence) f(line, number);
  }
}

/// UTF-8 sequences GitHub drops from anchors (punctuation and symbols seen in headings).
bool droppedSymbol(const std::string& utf8) {
  static const char* const kDropped[] = {"×", "—", "–", "→", "←", "·", "≤", "≥",
                                         "±", "…", "“", "”", "‘", "’", "°"};
  for (const char* s : kDropped)
    if (utf8 == s) return true;
  return false;
}

std::string slug(const std::string& heading) {
  std::string out;
  for (size_t i = 0; i < heading.size();) {
    const unsigned char c = static_cast<unsigned char>(heading[i]);
    if (c < 0x80) {
      if (std::isalnum(c) || c == '-' || c == '_')
        out += static_cast<char>(std::tolower(c));
      else if (c == ' ')
        out += '-';
      ++i;
      continue;
    }
    size_t length = (c >= 0xF0) ? 4 : (c >= 0xE0) ? 3 : (c >= 0xC0) ? 2 : 1;
    const std::string sequence = heading.substr(i, length);
    if (!droppedSymbol(sequence)) out += sequence;
    i += length;
  }
  return out;
}

std::string withoutInlineCode(const std::string& line) {
  std::string out;
  bool in_code = false;
  for (char c : line) {
    if (c == '`') {
      in_code = !in_code;
      continue;
    }
    if (!in_code) out += c;
  }
  return out;
}

}  // namespace

std::vector<std::string> markdownHeadingAnchors(const std::string& text) {
  std::vector<std::string> anchors;
  std::map<std::string, int> seen;
  static const std::regex kHeading(R"(^#{1,6}\s+(.*?)\s*#*\s*$)");
  forEachProseLine(text, [&](const std::string& line, int) {
    std::smatch m;
    if (!std::regex_match(line, m, kHeading)) return;
    const std::string base = slug(m[1].str());
    const int repeat = seen[base]++;
    anchors.push_back(repeat == 0 ? base : base + "-" + std::to_string(repeat));
  });
  return anchors;
}

std::vector<std::string> brokenRelativeLinks(const std::string& path) {
  std::vector<std::string> broken;
  std::string text;
  if (!readText(path, &text)) return {path + ": cannot be read"};
  const fs::path folder = fs::path(path).parent_path();
  static const std::regex kLink(R"(\]\(\s*<?([^)\s>]+)>?(?:\s+"[^"]*")?\s*\))");
  static const std::regex kScheme(R"(^[a-zA-Z][a-zA-Z0-9+.-]*:)");
  forEachProseLine(text, [&](const std::string& raw_line, int number) {
    const std::string line = withoutInlineCode(raw_line);
    for (auto it = std::sregex_iterator(line.begin(), line.end(), kLink);
         it != std::sregex_iterator(); ++it) {
      const std::string target = (*it)[1].str();
      if (std::regex_search(target, kScheme)) continue;  // http://, https://, mailto:
      const size_t hash = target.find('#');
      const std::string file_part = target.substr(0, hash);
      const std::string anchor = hash == std::string::npos ? "" : target.substr(hash + 1);
      const fs::path resolved = file_part.empty() ? fs::path(path) : folder / file_part;
      auto report = [&](const std::string& why) {
        broken.push_back(path + ":" + std::to_string(number) + ": " + target + " (" + why + ")");
      };
      if (!fs::exists(resolved)) {
        report("no such file");
        continue;
      }
      if (anchor.empty()) continue;
      std::string target_text;
      if (resolved.extension() != ".md" || !readText(resolved, &target_text)) {
        report("an anchor into a file that is not a Markdown page");
        continue;
      }
      const std::vector<std::string> anchors = markdownHeadingAnchors(target_text);
      if (std::find(anchors.begin(), anchors.end(), anchor) == anchors.end())
        report("no heading with this anchor");
    }
  });
  return broken;
}

}  // namespace stereo_fusion
