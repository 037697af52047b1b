// Replays fuzz inputs through a fuzz target without libFuzzer, so the normal (g++) build and
// CI keep every checked-in corpus file and every former crash as a regression test.
//   fuzz_<name>_replay <file or folder>...   (folders: every regular file in them, sorted)
// A missing folder counts as empty: a new target may not have found any crash yet.
// Each input has a time limit, like libFuzzer's -timeout (scripts/fuzz.sh): one input that runs
// longer fails the replay, naming it (STEREO_FUSION_FUZZ_INPUT_TIMEOUT_S, default 20 s, for the
// sanitizer builds' slowdown; the inputs are tiny).
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);
extern "C" __attribute__((weak)) int LLVMFuzzerInitialize(int* argc, char*** argv);

namespace {

char g_current[4096] = "";
unsigned g_timeout_s = 20;

void onTimeout(int) {
  // Only async-signal-safe calls here: write() and _exit().
  const char head[] = "fuzz replay: input ran longer than the per-input time limit: ";
  (void)!write(2, head, sizeof head - 1);
  (void)!write(2, g_current, strnlen(g_current, sizeof g_current));
  (void)!write(2, "\n", 1);
  _exit(1);
}

}  // namespace

int main(int argc, char** argv) {
  if (const char* limit = std::getenv("STEREO_FUSION_FUZZ_INPUT_TIMEOUT_S"))
    g_timeout_s = static_cast<unsigned>(std::strtoul(limit, nullptr, 10));
  signal(SIGALRM, onTimeout);
  if (LLVMFuzzerInitialize) LLVMFuzzerInitialize(&argc, &argv);
  namespace fs = std::filesystem;
  std::vector<fs::path> files;
  for (int i = 1; i < argc; ++i) {
    const fs::path arg(argv[i]);
    std::error_code ec;
    if (fs::is_directory(arg, ec)) {
      for (const auto& entry : fs::directory_iterator(arg))
        if (entry.is_regular_file()) files.push_back(entry.path());
    } else if (fs::exists(arg, ec)) {
      files.push_back(arg);
    }
  }
  std::sort(files.begin(), files.end());
  for (const fs::path& file : files) {
    std::ifstream in(file, std::ios::binary);
    const std::vector<char> bytes{std::istreambuf_iterator<char>(in),
                                  std::istreambuf_iterator<char>()};
    std::printf("replaying %s (%zu bytes)\n", file.c_str(), bytes.size());
    std::fflush(stdout);  // the last line names the input if the target crashes
    std::snprintf(g_current, sizeof g_current, "%s", file.c_str());
    alarm(g_timeout_s);
    LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
    alarm(0);
  }
  std::printf("%zu inputs replayed without a crash\n", files.size());
  return 0;
}
