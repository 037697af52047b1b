#include "stereo_fusion/rviz/MeshDisplay.h"

#include <OGRE/OgreManualObject.h>
#include <OGRE/OgreMaterialManager.h>
#include <OGRE/OgreResourceGroupManager.h>
#include <OGRE/OgreSceneManager.h>
#include <OGRE/OgreSceneNode.h>
#include <OGRE/OgreTechnique.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <rviz/display_context.h>
#include <rviz/frame_manager.h>
#include <rviz/properties/bool_property.h>
#include <rviz/properties/ros_topic_property.h>
#include <rviz/properties/string_property.h>
#include <stereo_fusion/GetFullMesh.h>

#include <atomic>

namespace stereo_fusion {

namespace {

/// A failed or unavailable ~get_full_mesh is retried this often (the robot may start later).
constexpr std::chrono::seconds kFetchRetry{2};
/// How long the fetch thread waits for the service to appear before giving up this round.
constexpr double kServiceWait_s = 1.0;

std::string uniqueName(const char* prefix) {
  static std::atomic<int> counter{0};
  return prefix + std::to_string(counter++);
}

}  // namespace

MeshDisplay::MeshDisplay() {
  service_property_ = new rviz::StringProperty(
      "Full mesh service", "",
      "stereo_fusion/GetFullMesh service fetched after a late start, a lost update or a restart "
      "of the publisher. Empty: the topic's namespace + get_full_mesh "
      "(/stereo_fusion/mesh_update -> /stereo_fusion/get_full_mesh).",
      this, SLOT(updateService()));
  lighting_property_ = new rviz::BoolProperty(
      "Lighting", true, "Shade the mesh by its normals; off: the vertex colours as they are.", this,
      SLOT(updateLighting()));
}

MeshDisplay::~MeshDisplay() {
  // The fetch thread uses no member but its own copies; wait for it so it ends before rviz.
  if (fetch_.valid()) fetch_.wait();
  if (initialized()) {
    destroyBlocks();
    if (root_) scene_manager_->destroySceneNode(root_);
    if (material_) Ogre::MaterialManager::getSingleton().remove(material_);
  }
}

void MeshDisplay::onInitialize() {
  MFDClass::onInitialize();
  root_ = scene_node_->createChildSceneNode();
  // rviz 1.14 on OGRE 1.12 has no "rviz" resource group: the default one, as its own displays.
  material_ = Ogre::MaterialManager::getSingleton().create(
      uniqueName("stereo_fusion_mesh_material_"),
      Ogre::ResourceGroupManager::DEFAULT_RESOURCE_GROUP_NAME);
  Ogre::Pass* pass = material_->getTechnique(0)->getPass(0);
  // The vertex colours are the surface's; light modulates them (ambient + diffuse).
  pass->setVertexColourTracking(Ogre::TVC_AMBIENT | Ogre::TVC_DIFFUSE);
  pass->setCullingMode(Ogre::CULL_NONE);  // both sides, as rviz's triangle-list markers
  updateLighting();
}

void MeshDisplay::updateLighting() {
  if (!material_) return;
  material_->getTechnique(0)->getPass(0)->setLightingEnabled(lighting_property_->getBool());
  context_->queueRender();
}

void MeshDisplay::updateService() {
  // A different service: whatever is held may come from another publisher.
  reset();
}

std::string MeshDisplay::fullMeshService() const {
  const std::string configured = service_property_->getStdString();
  if (!configured.empty()) return configured;
  const std::string topic = topic_property_->getTopicStd();
  const size_t slash = topic.rfind('/');
  return (slash == std::string::npos ? std::string() : topic.substr(0, slash + 1)) +
         "get_full_mesh";
}

void MeshDisplay::reset() {
  MFDClass::reset();
  follower_.reset();  // every held block becomes dirty
  redrawDirty();
  frame_id_.clear();
  // A fetch under way may ask another service (the topic changed): its reply is dropped.
  discard_fetch_ = fetch_.valid();
  last_fetch_start_ = {};
}

void MeshDisplay::processMessage(const MeshUpdate::ConstPtr& update) {
  frame_id_ = update->header.frame_id;
  if (follower_.update(*update) == MeshFollower::Outcome::kMalformed)
    setStatus(rviz::StatusProperty::Error, "Update",
              QString("malformed update %1 ignored (applyMeshUpdate refused it)")
                  .arg(static_cast<qulonglong>(update->sequence)));
  redrawDirty();
  startFetchIfDue();
  showStatus();
}

void MeshDisplay::update(float, float) {
  finishFetchIfDone();
  startFetchIfDue();
  if (frame_id_.empty()) return;
  // The mesh is in the publisher's world frame: posed at the newest transform every frame, so
  // a fixed frame chosen later (odom, base_link) follows without redrawing a block.
  Ogre::Vector3 position;
  Ogre::Quaternion orientation;
  if (context_->getFrameManager()->getTransform(frame_id_, ros::Time(), position, orientation)) {
    root_->setPosition(position);
    root_->setOrientation(orientation);
    setStatus(rviz::StatusProperty::Ok, "Transform", "OK");
  } else {
    setStatus(rviz::StatusProperty::Error, "Transform",
              QString::fromStdString("no transform from '" + frame_id_ + "' to '" +
                                     fixed_frame_.toStdString() + "'"));
  }
}

void MeshDisplay::startFetchIfDue() {
  if (!isEnabled() || !follower_.wantsFullMesh() || fetch_.valid()) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_fetch_start_ < kFetchRetry) return;
  last_fetch_start_ = now;
  fetch_service_ = fullMeshService();
  follower_.fetchStarted();
  const std::string service = fetch_service_;
  fetch_ = std::async(std::launch::async, [service]() -> std::optional<MeshUpdate> {
    ros::NodeHandle nh;
    ros::ServiceClient client = nh.serviceClient<GetFullMesh>(service);
    if (!client.waitForExistence(ros::Duration(kServiceWait_s))) return std::nullopt;
    GetFullMesh srv;
    if (!client.call(srv)) return std::nullopt;
    return srv.response.mesh;
  });
}

void MeshDisplay::finishFetchIfDone() {
  if (!fetch_.valid() || fetch_.wait_for(std::chrono::seconds(0)) != std::future_status::ready)
    return;
  std::optional<MeshUpdate> full = fetch_.get();
  if (discard_fetch_) {  // asked before a reset; the follower was not waiting for it
    discard_fetch_ = false;
    return;
  }
  if (full) {
    if (follower_.fullMeshArrived(*full) == MeshFollower::Outcome::kMalformed)
      setStatus(rviz::StatusProperty::Error, "Update",
                QString::fromStdString("malformed full mesh from " + fetch_service_));
    if (frame_id_.empty()) frame_id_ = full->header.frame_id;
  } else {
    ++fetch_failures_;
    follower_.fetchFailed();
  }
  redrawDirty();
  showStatus();
}

void MeshDisplay::redrawDirty() {
  if (!root_) return;
  for (const BlockKey& key : follower_.takeDirty()) {
    auto held = follower_.mesh().find(key);
    auto drawn = blocks_.find(key);
    if (held == follower_.mesh().end()) {
      if (drawn == blocks_.end()) continue;
      root_->detachObject(drawn->second);
      scene_manager_->destroyManualObject(drawn->second);
      blocks_.erase(drawn);
      continue;
    }
    if (drawn == blocks_.end()) {
      Ogre::ManualObject* object = scene_manager_->createManualObject();
      object->setDynamic(true);
      root_->attachObject(object);
      drawn = blocks_.emplace(key, object).first;
    }
    drawBlock(held->second, drawn->second);
  }
  context_->queueRender();
}

void MeshDisplay::drawBlock(const SubMesh& submesh, Ogre::ManualObject* object) {
  object->clear();
  object->estimateVertexCount(submesh.positions.size());
  object->estimateIndexCount(3 * submesh.triangles.size());
  object->begin(material_, Ogre::RenderOperation::OT_TRIANGLE_LIST);
  for (size_t v = 0; v < submesh.positions.size(); ++v) {
    const Eigen::Vector3f& p = submesh.positions[v];
    const Eigen::Vector3f& n = submesh.normals[v];
    const auto& c = submesh.colors[v];
    object->position(p.x(), p.y(), p.z());
    object->normal(n.x(), n.y(), n.z());
    object->colour(c[0] / 255.0f, c[1] / 255.0f, c[2] / 255.0f);
  }
  for (const auto& t : submesh.triangles) object->triangle(t[0], t[1], t[2]);
  object->end();
}

void MeshDisplay::destroyBlocks() {
  for (const auto& [key, object] : blocks_) {
    root_->detachObject(object);
    scene_manager_->destroyManualObject(object);
  }
  blocks_.clear();
}

void MeshDisplay::showStatus() {
  size_t triangles = 0;
  for (const auto& [key, submesh] : follower_.mesh()) triangles += submesh.triangles.size();
  setStatus(rviz::StatusProperty::Ok, "Mesh",
            QString("%1 blocks, %2 triangles").arg(follower_.mesh().size()).arg(triangles));
  if (follower_.synced())
    setStatus(
        rviz::StatusProperty::Ok, "Sync",
        QString("in sync at sequence %1").arg(static_cast<qulonglong>(follower_.lastSequence())));
  else if (follower_.fetching())
    setStatus(rviz::StatusProperty::Warn, "Sync",
              QString::fromStdString("fetching the full mesh from " + fetch_service_));
  else
    setStatus(rviz::StatusProperty::Warn, "Sync",
              QString("not in sync: drawing the updates as they come; the full mesh from %1 "
                      "failed %2 times (retried every %3 s)")
                  .arg(QString::fromStdString(fullMeshService()))
                  .arg(static_cast<qulonglong>(fetch_failures_))
                  .arg(kFetchRetry.count()));
  const uint64_t lost = follower_.gaps() + follower_.queueDropped();
  if (lost + follower_.restarts() + follower_.malformed() > 0)
    setStatus(rviz::StatusProperty::Warn, "Lost updates",
              QString("%1 missed (sequence gaps), %2 dropped while fetching, %3 malformed, "
                      "%4 publisher restarts")
                  .arg(static_cast<qulonglong>(follower_.gaps()))
                  .arg(static_cast<qulonglong>(follower_.queueDropped()))
                  .arg(static_cast<qulonglong>(follower_.malformed()))
                  .arg(static_cast<qulonglong>(follower_.restarts())));
}

}  // namespace stereo_fusion

PLUGINLIB_EXPORT_CLASS(stereo_fusion::MeshDisplay, rviz::Display)
