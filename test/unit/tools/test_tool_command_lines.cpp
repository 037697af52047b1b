// Every command-line tool, run as its binary: --help prints the usage and exits 0, an unknown
// option is refused with exit code 2 and named, and so is a malformed or negative number.
// The tools are built beside this test (STEREO_FUSION_TOOL_DIR, CMakeLists.txt).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

/// A tool and arguments that make its command line complete but for the option tested.
struct Tool {
  std::string binary;
  std::vector<std::string> required;  ///< positional paths and required options
  std::string number_option;          ///< an option taking a number; empty: it has none
};

/// How gtest (and so the ctest names) shows a tool.
void PrintTo(const Tool& tool, std::ostream* out) { *out << tool.binary; }

/// What a run printed and how it ended.
struct ToolRun {
  int exit_code = -1;
  std::string out, err;
};

std::string quoted(const std::string& text) {
  std::string q = "'";
  for (char c : text) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string readFile(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Scratch space of this process (ctest runs the cases in parallel, each its own process).
fs::path scratch() {
  const fs::path dir =
      fs::path(testing::TempDir()) / ("stereo_fusion_command_lines_" + std::to_string(getpid()));
  fs::create_directories(dir);
  return dir;
}

ToolRun runTool(const Tool& tool, const std::vector<std::string>& args) {
  const fs::path binary = fs::path(STEREO_FUSION_TOOL_DIR) / tool.binary;
  EXPECT_TRUE(fs::exists(binary)) << binary;
  const fs::path out = scratch() / "stdout.txt", err = scratch() / "stderr.txt";
  std::string command = quoted(binary.string());
  for (const std::string& a : args) command += " " + quoted(a);
  command += " < /dev/null > " + quoted(out.string()) + " 2> " + quoted(err.string());
  const int status = std::system(command.c_str());
  ToolRun r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = readFile(out);
  r.err = readFile(err);
  return r;
}

std::vector<std::string> with(const Tool& tool, const std::vector<std::string>& more) {
  std::vector<std::string> args = tool.required;
  args.insert(args.end(), more.begin(), more.end());
  return args;
}

/// Output files of a run that should never start go here (were one to start).
const std::string kNowhere =
    (fs::path(testing::TempDir()) / "stereo_fusion_never_written").string();

const std::vector<Tool> kTools = {
    {"stereo_fusion_fuse", {"seq", kNowhere}, "--frames"},
    {"stereo_fusion_evaluate", {"mesh.ply", "seq"}, "--tolerance-m"},
    {"stereo_fusion_evaluate_esdf", {"esdf.ply"}, "--max-distance-m"},
    {"stereo_fusion_simulate", {"--out", kNowhere}, "--frames"},
    {"stereo_fusion_texture_compare", {"seq", kNowhere}, "--views"},
    {"stereo_fusion_soak", {"--csv", kNowhere + ".csv"}, "--frames"},
    {"stereo_fusion_planning_probe", {}, "--duration-s"},
    {"stereo_fusion_parameters", {}, ""},
};

std::vector<Tool> toolsWithNumbers() {
  std::vector<Tool> tools;
  for (const Tool& tool : kTools)
    if (!tool.number_option.empty()) tools.push_back(tool);
  return tools;
}

std::string lowered(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

std::string testName(const testing::TestParamInfo<Tool>& info) {
  return info.param.binary.substr(std::string("stereo_fusion_").size());
}

class ToolCommandLine : public testing::TestWithParam<Tool> {};
class ToolNumbers : public testing::TestWithParam<Tool> {};

}  // namespace

TEST_P(ToolCommandLine, HelpPrintsTheUsageAndExitsZero) {
  const Tool& tool = GetParam();
  const ToolRun r = runTool(tool, {"--help"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(lowered(r.out).find("usage: " + tool.binary), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("--help"), std::string::npos) << r.out;
  // What each option means is in the help, the option with a number too.
  if (!tool.number_option.empty()) {
    EXPECT_NE(r.out.find(tool.number_option), std::string::npos) << r.out;
  }
}

TEST_P(ToolCommandLine, UnknownOptionIsRefusedWithExitCodeTwo) {
  const Tool& tool = GetParam();
  const ToolRun r = runTool(tool, with(tool, {"--no-such-option"}));
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("--no-such-option"), std::string::npos) << r.err;
}

TEST_P(ToolNumbers, MalformedOrNegativeNumberIsRefusedNamingTheOption) {
  const Tool& tool = GetParam();
  for (const char* bad : {"abc", "-3", "1x"}) {
    const ToolRun r = runTool(tool, with(tool, {tool.number_option, bad}));
    EXPECT_EQ(r.exit_code, 2) << tool.number_option << " " << bad << ": " << r.out << r.err;
    EXPECT_NE(r.err.find(tool.number_option), std::string::npos) << r.err;
  }
}

INSTANTIATE_TEST_SUITE_P(Tools, ToolCommandLine, testing::ValuesIn(kTools), testName);
INSTANTIATE_TEST_SUITE_P(Tools, ToolNumbers, testing::ValuesIn(toolsWithNumbers()), testName);
