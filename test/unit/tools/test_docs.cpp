// The user documentation stays true to the code and to itself: doc/parameters.md is exactly the
// page generated from the parameter registries (mapping and node parameters), every relative
// link of README.md and doc/ resolves (file and heading anchor), every service the nodes
// advertise and every node parameter is named where the pages list them, every option of the
// offline tools' --help is in offline_tools.md, and figures stated on several pages agree.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "docs/MarkdownLinks.h"
#include "docs/ParameterPage.h"
#include "stereo_fusion/MapperConfig.h"
#include "stereo_fusion/ros/RosParameters.h"

using namespace stereo_fusion;
namespace fs = std::filesystem;

namespace {

const std::string kSourceDir = STEREO_FUSION_SOURCE_DIR;

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// README.md and every Markdown page under doc/.
std::vector<fs::path> documentationPages() {
  std::vector<fs::path> pages{fs::path(kSourceDir) / "README.md"};
  for (const auto& entry : fs::recursive_directory_iterator(fs::path(kSourceDir) / "doc"))
    if (entry.path().extension() == ".md") pages.push_back(entry.path());
  return pages;
}

/// The text of `page` from its heading `heading` (a whole line) to the next heading of the same
/// level; empty when the heading is missing.
std::string section(const std::string& page, const std::string& heading) {
  const size_t start = page.find("\n" + heading + "\n");
  if (start == std::string::npos) return "";
  const std::string level = heading.substr(0, heading.find(' ') + 1);
  const size_t end = page.find("\n" + level, start + heading.size() + 1);
  return page.substr(start, end == std::string::npos ? std::string::npos : end - start);
}

/// Every "--option" a text names, "--help" aside.
std::set<std::string> optionsIn(const std::string& text) {
  std::set<std::string> options;
  const std::regex option(R"((^|[^A-Za-z0-9-])(--[a-z][a-z0-9-]*))");
  for (std::sregex_iterator it(text.begin(), text.end(), option), end; it != end; ++it)
    if ((*it)[2] != "--help") options.insert((*it)[2]);
  return options;
}

/// What `binary --help` prints.
std::string helpOf(const std::string& binary) {
  const std::string command =
      "'" + (fs::path(STEREO_FUSION_TOOL_DIR) / binary).string() + "' --help";
  std::string out;
  if (FILE* pipe = ::popen(command.c_str(), "r")) {
    char buffer[4096];
    size_t n;
    while ((n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) out.append(buffer, n);
    ::pclose(pipe);
  }
  return out;
}

/// `text` without spaces and line breaks (so "31 – 39 ms" and "31–39\nms" compare equal).
std::string withoutSpaces(std::string text) {
  text.erase(std::remove_if(text.begin(), text.end(), [](char c) { return c == ' ' || c == '\n'; }),
             text.end());
  return text;
}

}  // namespace

TEST(Docs, ParameterPageIsGeneratedFromTheRegistry) {
  const std::string page = readFile(fs::path(kSourceDir) / "doc" / "parameters.md");
  EXPECT_EQ(page, parameterPageMarkdown())
      << "doc/parameters.md differs from the parameter registry: regenerate it with "
         ".build/devel/lib/stereo_fusion/stereo_fusion_parameters --markdown > doc/parameters.md";
  const size_t node_section = page.find("\n## Node parameters\n");
  ASSERT_NE(node_section, std::string::npos) << "doc/parameters.md: the node parameters' section";
  for (const ParameterSpec& spec : mapperParameterSpecs())
    EXPECT_LT(page.find("| `" + spec.name + "` |"), node_section) << spec.name;
  // The nodelet's own parameters, from their registry, with their units and ranges.
  const NodeConfig node_defaults;
  for (const ParameterSpec& spec : nodeParameterSpecs()) {
    const std::string value = getNodeParameter(node_defaults, spec.name);
    const std::string row = "| `" + spec.name + "` | " + (spec.unit.empty() ? "–" : spec.unit) +
                            " | " + (value.empty() ? "(empty)" : "`" + value + "`") + " | ";
    const size_t at = page.find(row);
    EXPECT_NE(at, std::string::npos) << row;
    EXPECT_GT(at, node_section) << spec.name;
  }
  EXPECT_NE(page.find("| `queue_size` | frames | `5` | [1, 1000] |"), std::string::npos);
  EXPECT_NE(page.find("| `tf_timeout_s` | s | `0.2` | [0, 10] |"), std::string::npos);
}

TEST(Docs, EveryRelativeLinkResolves) {
  const std::vector<fs::path> pages = documentationPages();
  ASSERT_GE(pages.size(), 5u) << "README.md and the doc/ pages";
  for (const fs::path& page : pages)
    for (const std::string& broken : brokenRelativeLinks(page.string())) ADD_FAILURE() << broken;
}

// The README is the landing page; the reference lives in doc/.
TEST(Docs, ReadmeStaysALandingPage) {
  const std::string readme = readFile(fs::path(kSourceDir) / "README.md");
  EXPECT_LE(std::count(readme.begin(), readme.end(), '\n'), 200)
      << "README.md: move reference material into doc/";
}

// The checker itself: it must see a missing file, a missing anchor and a link into a page's
// own headings, and ignore code and absolute URLs.
TEST(Docs, LinkCheckerReportsWhatDoesNotResolve) {
  const fs::path folder =
      fs::temp_directory_path() / ("stereo_fusion_docs_" + std::to_string(::getpid()));
  fs::create_directories(folder / "sub");
  std::ofstream(folder / "sub" / "target.md")
      << "# Target page\n\n## Speed & memory — 2 cm\n\n## Speed & memory — 2 cm\n";
  std::ofstream(folder / "page.md")
      << "# Page\n\n## A heading\n\n"
         "[ok](sub/target.md) [ok](sub/target.md#target-page) "
         "[ok](sub/target.md#speed--memory--2-cm-1)\n"
         "[ok](#a-heading) [ok](sub/) [web](https://example.org/missing.md) `[code](missing.md)`\n"
         "[bad file](sub/missing.md)\n"
         "[bad anchor](sub/target.md#no-such-heading)\n"
         "```\n[in a fence](missing.md)\n```\n"
         "[bad own anchor](#nowhere)\n";
  const std::vector<std::string> broken = brokenRelativeLinks((folder / "page.md").string());
  fs::remove_all(folder);
  ASSERT_EQ(broken.size(), 3u);
  EXPECT_NE(broken[0].find(":7: sub/missing.md (no such file)"), std::string::npos) << broken[0];
  EXPECT_NE(broken[1].find(":8: sub/target.md#no-such-heading (no heading with this anchor)"),
            std::string::npos)
      << broken[1];
  EXPECT_NE(broken[2].find(":12: #nowhere"), std::string::npos) << broken[2];
}

TEST(Docs, HeadingAnchorsFollowTheForges) {
  EXPECT_EQ(markdownHeadingAnchors(
                "# Quick start\n## The method, as implemented\n### `fuse.sh` — offline\n"
                "## Quick start\n"),
            (std::vector<std::string>{"quick-start", "the-method-as-implemented", "fusesh--offline",
                                      "quick-start-1"}));
}

// Every service a node advertises (src/ros/: advertiseService("name", ...)) is in
// ros_interface.md's table as `~name` and in development.md's list, and every service type
// (srv/*.srv) is in development.md.
TEST(Docs, EveryAdvertisedServiceIsDocumented) {
  const std::string ros_interface = readFile(fs::path(kSourceDir) / "doc" / "ros_interface.md");
  const std::string development = readFile(fs::path(kSourceDir) / "doc" / "development.md");
  const std::regex advertise(R"re(advertiseService\(\s*"([a-z_]+)")re");
  std::set<std::string> services;
  for (const auto& entry : fs::directory_iterator(fs::path(kSourceDir) / "src" / "ros")) {
    const std::string code = readFile(entry.path());
    for (std::sregex_iterator it(code.begin(), code.end(), advertise), end; it != end; ++it)
      services.insert((*it)[1]);
  }
  EXPECT_GE(services.size(), 9u) << "the nodelet's nine services, at least";
  for (const std::string& name : services) {
    EXPECT_NE(ros_interface.find("| `~" + name + "` |"), std::string::npos)
        << "~" << name << ": no row in doc/ros_interface.md";
    EXPECT_NE(development.find("~" + name), std::string::npos)
        << "~" << name << ": not in doc/development.md";
  }
  size_t types = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(kSourceDir) / "srv")) {
    ++types;
    EXPECT_NE(development.find(entry.path().stem().string()), std::string::npos)
        << entry.path().filename() << ": not in doc/development.md";
  }
  EXPECT_GE(types, 8u);
}

// ros_interface.md's "Node parameters" names every node parameter (the table itself is
// parameters.md, generated).
TEST(Docs, RosInterfaceNamesEveryNodeParameter) {
  const std::string text =
      section(readFile(fs::path(kSourceDir) / "doc" / "ros_interface.md"), "## Node parameters");
  ASSERT_FALSE(text.empty());
  for (const ParameterSpec& spec : nodeParameterSpecs())
    EXPECT_NE(text.find("`" + spec.name + "`"), std::string::npos) << spec.name;
}

// The offline tools' reference is offline_tools.md: every option their --help lists is there.
TEST(Docs, EveryOptionOfTheOfflineToolsIsInOfflineTools) {
  const std::string page = readFile(fs::path(kSourceDir) / "doc" / "offline_tools.md");
  for (const char* tool :
       {"stereo_fusion_fuse", "stereo_fusion_evaluate", "stereo_fusion_evaluate_esdf"}) {
    const std::set<std::string> options = optionsIn(helpOf(tool));
    EXPECT_GE(options.size(), 3u) << tool << " --help";
    for (const std::string& option : options)
      EXPECT_NE(page.find(option), std::string::npos)
          << tool << " " << option << ": not in doc/offline_tools.md";
  }
  // The extraction itself: options in prose and usage lines, not words with dashes.
  EXPECT_EQ(optionsIn("a --max-distance-m D, [--json F] well-known --help"),
            (std::set<std::string>{"--json", "--max-distance-m"}));
}

// The 100 000-point ~get_distance time is one figure: the live measurement's p50 (the table of
// "Planning interface, live"), repeated in the service's row and the README.
TEST(Docs, GetDistanceTimeIsTheLiveMeasurementEverywhere) {
  const std::string ros_interface = readFile(fs::path(kSourceDir) / "doc" / "ros_interface.md");
  const std::string live = section(ros_interface, "## Planning interface, live");
  std::smatch row;
  ASSERT_TRUE(std::regex_search(live, row,
                                std::regex(R"(\| 100 000 \| [0-9]+ \| ([0-9.]+ – [0-9.]+ ms) \|)")))
      << "the live table's 100 000-point row";
  const std::string p50 = withoutSpaces(row[1]);
  const size_t service_row = ros_interface.find("| `~get_distance` |");
  ASSERT_NE(service_row, std::string::npos);
  const std::string service =
      ros_interface.substr(service_row, ros_interface.find('\n', service_row) - service_row);
  EXPECT_NE(withoutSpaces(service).find("100000pointstake" + p50), std::string::npos) << service;
  const std::string readme = readFile(fs::path(kSourceDir) / "README.md");
  EXPECT_NE(withoutSpaces(readme).find("100000pointscomebackin" + p50), std::string::npos)
      << "README.md: 100 000 points come back in " << row[1].str();
}

// How long the first demo and test runs take is kept in one place, getting_started.md: the
// README's "Try it" and setup.sh's messages state no duration of their own.
TEST(Docs, FirstRunTimesAreKeptInGettingStartedOnly) {
  const std::regex duration(R"(([0-9]+\s*(–|-|to)\s*)?[0-9]+\s*(minutes|min\b|m [0-9]+ s))");
  const std::string try_it = section(readFile(fs::path(kSourceDir) / "README.md"), "## Try it");
  ASSERT_FALSE(try_it.empty());
  std::smatch found;
  EXPECT_FALSE(std::regex_search(try_it, found, duration)) << "README.md: " << found.str();
  EXPECT_NE(try_it.find("doc/getting_started.md#setup-demo-and-tests"), std::string::npos);
  const std::string setup = readFile(fs::path(kSourceDir) / "scripts" / "setup.sh");
  EXPECT_FALSE(std::regex_search(setup, found, duration)) << "scripts/setup.sh: " << found.str();
  const std::string started = section(readFile(fs::path(kSourceDir) / "doc" / "getting_started.md"),
                                      "## Setup, demo and tests");
  EXPECT_TRUE(std::regex_search(started, found, duration)) << "getting_started.md: the times";
}
