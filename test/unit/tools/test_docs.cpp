// The user documentation stays true to the code and to itself: doc/parameters.md is exactly the
// page generated from the parameter registries (mapping and node parameters), and every
// relative link of README.md and doc/ resolves (file and heading anchor).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
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
