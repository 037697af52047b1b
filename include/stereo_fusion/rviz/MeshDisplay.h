#pragma once
// rviz display `stereo_fusion/Mesh`: draws ~mesh_update (stereo_fusion/MeshUpdate) directly,
// one Ogre::ManualObject per block, vertex-coloured and lit by the message's normals. Only the
// blocks an update carries are rebuilt; the bookkeeping (replace, remove, full, sessions,
// sequence gaps) is MeshFollower's. A late start, a gap or a robot restart fetches the whole
// mesh from the publisher's ~get_full_mesh in a thread of its own, so rviz never waits on it.

#ifndef Q_MOC_RUN
#include <OGRE/OgreMaterial.h>
#include <rviz/message_filter_display.h>
#include <stereo_fusion/MeshUpdate.h>

#include <chrono>
#include <future>
#include <optional>
#include <string>
#include <unordered_map>

#include "stereo_fusion/ros/MeshFollower.h"
#endif

namespace Ogre {
class ManualObject;
class SceneNode;
}  // namespace Ogre

namespace rviz {
class BoolProperty;
class StringProperty;
}  // namespace rviz

namespace stereo_fusion {

class MeshDisplay : public rviz::MessageFilterDisplay<MeshUpdate> {
  Q_OBJECT
 public:
  MeshDisplay();
  ~MeshDisplay() override;

 protected:
  void onInitialize() override;
  void reset() override;
  void update(float wall_dt, float ros_dt) override;

 private Q_SLOTS:
  void updateLighting();
  void updateService();

 private:
  void processMessage(const MeshUpdate::ConstPtr& update) override;
  /// Rebuilds or erases the drawing of every block MeshFollower reports dirty.
  void redrawDirty();
  void drawBlock(const SubMesh& submesh, Ogre::ManualObject* object);
  void destroyBlocks();
  /// The full-mesh service: the property, else the topic's namespace + get_full_mesh.
  std::string fullMeshService() const;
  void startFetchIfDue();
  void finishFetchIfDone();
  void showStatus();

  MeshFollower follower_;
  std::unordered_map<BlockKey, Ogre::ManualObject*, BlockKeyHash> blocks_;
  Ogre::SceneNode* root_ = nullptr;  ///< child of scene_node_, posed at the mesh's frame
  Ogre::MaterialPtr material_;
  std::string frame_id_;  ///< of the last update: the publisher's world frame

  std::future<std::optional<MeshUpdate>> fetch_;
  std::string fetch_service_;
  std::chrono::steady_clock::time_point last_fetch_start_{};
  uint64_t fetch_failures_ = 0;
  bool discard_fetch_ = false;  ///< the fetch under way was started before reset()

  rviz::StringProperty* service_property_ = nullptr;
  rviz::BoolProperty* lighting_property_ = nullptr;
};

}  // namespace stereo_fusion
