// Files are written only where a regular file may be: a FIFO nobody reads would block the
// writer (and with it fusion), a device node would be written into or replaced by a rename.
// Map files are refused from their header before their payload is read.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "MeshTestSupport.h"
#include "stereo_fusion/io/MapFile.h"
#include "stereo_fusion/io/MeshExport.h"
#include "stereo_fusion/io/WriteTarget.h"

using namespace stereo_fusion;
using namespace stereo_fusion::test;
namespace fs = std::filesystem;

namespace {

fs::path freshDir(const std::string& name) {
  const fs::path dir =
      fs::path(testing::TempDir()) / ("stereo_fusion_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

long maxRssKb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;
}

}  // namespace

TEST(WriteTarget, OnlyAbsentPathsAndRegularFilesAreWritable) {
  const fs::path dir = freshDir("targets");
  std::string error;
  EXPECT_TRUE(isWritableTarget((dir / "new.ply").string(), &error));
  std::ofstream(dir / "old.ply") << "x";
  EXPECT_TRUE(isWritableTarget((dir / "old.ply").string(), &error));
  ASSERT_EQ(::mkfifo((dir / "fifo.ply").c_str(), 0644), 0);
  EXPECT_FALSE(isWritableTarget((dir / "fifo.ply").string(), &error));
  EXPECT_NE(error.find("fifo.ply is a FIFO: only regular files are written"), std::string::npos)
      << error;
  EXPECT_FALSE(isWritableTarget("/dev/null", &error));
  EXPECT_NE(error.find("/dev/null is a device"), std::string::npos) << error;
  EXPECT_FALSE(isWritableTarget(dir.string(), &error));
  EXPECT_NE(error.find("is a directory"), std::string::npos) << error;
  fs::create_symlink(dir / "fifo.ply", dir / "link.ply");
  EXPECT_FALSE(isWritableTarget((dir / "link.ply").string(), &error))
      << "a link is judged by what it points to";
  EXPECT_NE(temporaryPathBeside((dir / "a.map").string()),
            temporaryPathBeside((dir / "a.map").string()));
  fs::remove_all(dir);
}

// Neither the map nor the mesh export opens a FIFO (which would block until a reader comes) or
// replaces it; the failure says why and nothing is left behind.
TEST(WriteTarget, MapAndMeshExportsRefuseAFifoWithoutBlocking) {
  const fs::path dir = freshDir("fifo_exports");
  const auto mapper = fusedMapper(2, MapperConfig{});
  ASSERT_GT(mapper->mesh().submeshes().size(), 10u);
  for (const char* name : {"map.sfmap", "mesh.ply", "mesh.obj", "mesh.mtl"}) {
    ASSERT_EQ(::mkfifo((dir / name).c_str(), 0644), 0) << name;
  }
  std::string error;
  EXPECT_FALSE(mapper->saveMap((dir / "map.sfmap").string(), &error));
  EXPECT_NE(error.find("map.sfmap is a FIFO"), std::string::npos) << error;
  EXPECT_FALSE(exportMesh((dir / "mesh.ply").string(), mapper->mesh().submeshes(), {}, &error));
  EXPECT_NE(error.find("mesh.ply is a FIFO"), std::string::npos) << error;
  std::remove((dir / "mesh.obj").c_str());
  std::ofstream(dir / "mesh.obj") << "old";
  EXPECT_FALSE(exportMesh((dir / "mesh.obj").string(), mapper->mesh().submeshes(), {}, &error));
  EXPECT_NE(error.find("mesh.mtl is a FIFO"), std::string::npos) << error;
  EXPECT_TRUE(fs::is_fifo(dir / "map.sfmap"));
  EXPECT_TRUE(fs::is_fifo(dir / "mesh.ply"));
  EXPECT_EQ(fs::file_size(dir / "mesh.obj"), 3u)
      << "nothing was written when one target was refused";
  for (const auto& entry : fs::directory_iterator(dir))
    EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos) << entry.path();
  // A regular target is written, through a temporary renamed into place.
  EXPECT_TRUE(exportMesh((dir / "good.ply").string(), mapper->mesh().submeshes(), {}, &error))
      << error;
  EXPECT_GT(fs::file_size(dir / "good.ply"), 1000u);
  fs::remove_all(dir);
}

// A refusal names the file the user gave and the OS's cause, never the internal temporary: a
// folder nobody may create files in (/proc refuses root too), and a writer failing half-way.
TEST(WriteTarget, RefusalsNameTheUsersFileAndTheCause) {
  const auto mapper = fusedMapper(2, MapperConfig{});
  std::string error;
  const std::string refused = "/proc/stereo_fusion_refused.ply";
  EXPECT_FALSE(exportMesh(refused, mapper->mesh().submeshes(), {}, &error));
  EXPECT_EQ(error.rfind(refused + ": cannot write the mesh (", 0), 0u) << error;
  EXPECT_NE(error.find(" ("), std::string::npos) << "the OS's cause: " << error;
  EXPECT_EQ(error.find(".tmp-"), std::string::npos) << error;

  const fs::path dir = freshDir("failing_writer");
  const std::string target = (dir / "out.bin").string();
  EXPECT_FALSE(writeThroughTemporary(
      target, "test file",
      [](const std::string& temporary, std::string* e) {
        *e = temporary + ": write failed (No space left on device)";
        return false;
      },
      &error));
  EXPECT_EQ(error, target + ": write failed (No space left on device)");
  for (const auto& entry : fs::directory_iterator(dir))
    ADD_FAILURE() << "left behind: " << entry.path();
  fs::remove_all(dir);
}

// A huge file is refused from its first 80 bytes: a sparse 64 GiB file of zeros (bad magic), and
// a real map file grown to 1 GiB (its header announces another size), without reading either.
TEST(MapFile, HugeFilesAreRefusedFromTheirHeaderWithoutBeingRead) {
  const fs::path dir = freshDir("huge_maps");
  const MapperConfig config;
  const auto mapper = fusedMapper(2, config);
  std::string error;
  const fs::path zeros = dir / "zeros.sfmap", grown = dir / "grown.sfmap";
  { std::ofstream(zeros) << ""; }
  fs::resize_file(zeros, uint64_t{64} << 30);
  ASSERT_TRUE(mapper->saveMap(grown.string(), &error)) << error;
  const uintmax_t real_size = fs::file_size(grown);
  fs::resize_file(grown, uint64_t{1} << 30);
  const long rss_before_kb = maxRssKb();
  BlockOctree out(config.blockSizeM());
  MapFileInfo info;
  EXPECT_FALSE(readMapFile(zeros.string(), config, &out, &info, &error));
  EXPECT_NE(error.find("bad magic"), std::string::npos) << error;
  EXPECT_FALSE(readMapFile(grown.string(), config, &out, &info, &error));
  EXPECT_NE(error.find("corrupted map file: 1073741824 bytes, but the header announces"),
            std::string::npos)
      << error;
  EXPECT_LT(maxRssKb() - rss_before_kb, 64 * 1024) << "the payload must not have been read";
  EXPECT_EQ(out.blockCount(), 0u);
  fs::resize_file(grown, real_size);
  EXPECT_TRUE(readMapFile(grown.string(), config, &out, &info, &error)) << error;
  fs::remove_all(dir);
}
