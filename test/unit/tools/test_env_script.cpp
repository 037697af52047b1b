// scripts/env.sh, sourced with the environment of each machine of a setup: it sets
// ROS_HOSTNAME=localhost only for a master on this machine with neither ROS_IP nor ROS_HOSTNAME
// given; a robot and a base station on two hosts keep what they set (localhost would send the
// other side to itself), and a remote master without either gets a hint on stderr.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

namespace {

const std::string kSourceDir = STEREO_FUSION_SOURCE_DIR;

/// "ROS_HOSTNAME=<value or unset> ROS_IP=<value or unset>" after sourcing env.sh with `env` (a
/// list of VAR=value) in a clean environment, then whatever it wrote to stderr. BUILD_DIR points
/// at a stand-in devel space, so no build is needed.
std::string sourceEnv(const std::string& env, const fs::path& build_dir) {
  const std::string command =
      "env -u ROS_HOSTNAME -u ROS_IP -u ROS_MASTER_URI BUILD_DIR=" + build_dir.string() + " " +
      env + " bash -c 'source " + kSourceDir +
      "/scripts/env.sh && echo \"ROS_HOSTNAME=${ROS_HOSTNAME-unset} ROS_IP=${ROS_IP-unset}\"' "
      "2>&1";
  std::string out;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return "popen failed";
  std::array<char, 512> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe) != nullptr) out += buffer.data();
  ::pclose(pipe);
  return out;
}

}  // namespace

TEST(EnvScript, LocalhostOnlyForALocalMasterWithoutAnAddress) {
  const fs::path build_dir =
      fs::temp_directory_path() / ("stereo_fusion_env_" + std::to_string(::getpid()));
  fs::create_directories(build_dir / "devel");
  std::ofstream(build_dir / "devel" / "setup.bash") << "# stand-in\n";
  const std::string local = "ROS_HOSTNAME=localhost ROS_IP=unset\n";
  EXPECT_EQ(sourceEnv("", build_dir), local) << "no master set: roscore on this machine";
  EXPECT_EQ(sourceEnv("ROS_MASTER_URI=http://localhost:11311", build_dir), local);
  EXPECT_EQ(sourceEnv("ROS_MASTER_URI=http://127.0.0.1:40123", build_dir), local);
  EXPECT_EQ(sourceEnv("ROS_MASTER_URI=http://[::1]:11311", build_dir), local);
  // Two machines: what the user set stays, and nothing is forced.
  EXPECT_EQ(sourceEnv("ROS_MASTER_URI=http://192.168.1.5:11311 ROS_IP=192.168.1.7", build_dir),
            "ROS_HOSTNAME=unset ROS_IP=192.168.1.7\n");
  EXPECT_EQ(sourceEnv("ROS_IP=10.0.0.2", build_dir), "ROS_HOSTNAME=unset ROS_IP=10.0.0.2\n");
  EXPECT_EQ(sourceEnv("ROS_HOSTNAME=basestation.lan", build_dir),
            "ROS_HOSTNAME=basestation.lan ROS_IP=unset\n");
  const std::string remote = sourceEnv("ROS_MASTER_URI=http://robot.lan:11311", build_dir);
  EXPECT_NE(remote.find("ROS_HOSTNAME=unset ROS_IP=unset\n"), std::string::npos) << remote;
  EXPECT_NE(remote.find("set ROS_IP (or ROS_HOSTNAME)"), std::string::npos) << remote;
  EXPECT_NE(remote.find("robot.lan"), std::string::npos) << remote;
  fs::remove_all(build_dir);
}
