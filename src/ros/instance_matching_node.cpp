#include "semantic_exploration/ros/instance_matching_node.hpp"

#include <sensor_msgs/image_encodings.h>

#include <cstring>
#include <unordered_set>

#include "semantic_exploration/MatchedDetections.h"
#include "semantic_exploration/core/instance_matching.hpp"
#include "semantic_exploration/ros/conversions.hpp"

namespace semexp_ros {

namespace enc = sensor_msgs::image_encodings;

InstanceMatchingNode::InstanceMatchingNode(ros::NodeHandle& nh, ros::NodeHandle& pnh)
    : CameraNode(nh, pnh, BeforeCameraInfo::kUseParameters, true), nh_(nh) {
  const auto& p = params();
  config_ = loadMatching(p);
  classes_ = loadClasses(p);
  matched_pub_ = nh.advertise<semantic_exploration::MatchedDetections>("matched_detections", 10);
  detections_sub_.subscribe(nh, "detections", 5);
  depth_sub_.subscribe(nh, "camera/depth/image_raw", 5);
  sync_ = makeSync<SyncPolicy>(loadImageSync(p).max_interval_s, detections_sub_, depth_sub_);
  sync_->registerCallback(&InstanceMatchingNode::frameCallback, this);
  ROS_INFO("instance_matching: iou_threshold %.2f, min_mask_pixels %d, fragment_fraction %.2f",
           config_.iou_threshold, config_.min_mask_pixels, config_.fragment_fraction);
}

bool InstanceMatchingNode::callRender(semantic_exploration::RenderInstances& srv) {
  // One persistent connection for all frames. A new connection per call sometimes loses the reply in roscpp
  // (a "Buffer Overrun" while deserializing it, ros/ros_comm#1976); a broken connection is reopened and the
  // call tried once more, so neither that nor an object_map restart costs a frame.
  for (int attempt = 0; attempt < 2; ++attempt) {
    if (!render_client_.isValid())
      render_client_ = nh_.serviceClient<semantic_exploration::RenderInstances>("object_map/render_instances", true);
    if (render_client_.call(srv)) return true;
    render_client_.shutdown();
  }
  return false;
}

void InstanceMatchingNode::publishEmpty(const std_msgs::Header& header, int width_px, int height_px) {
  // The frame still reaches object_map (visible objects are updated as
  // undetected and lockstep sees the frame handled).
  semantic_exploration::MatchedDetections empty;
  empty.header = header;
  empty.instance_image.header = header;
  empty.instance_image.width = static_cast<uint32_t>(width_px);
  empty.instance_image.height = static_cast<uint32_t>(height_px);
  empty.instance_image.encoding = enc::TYPE_16UC1;
  empty.instance_image.step = static_cast<uint32_t>(width_px * 2);
  empty.instance_image.data.assign(static_cast<size_t>(width_px) * height_px * 2, 0);
  matched_pub_.publish(empty);
}

void InstanceMatchingNode::frameCallback(const semantic_exploration::DetectionsConstPtr& msg,
                                         const sensor_msgs::ImageConstPtr& depth_msg) {
  // The empty answer of a failed frame has the depth frame's size once it decoded (the camera's before).
  const FrameTimer timer;  // reported for the CPU budget; object_map charges the render to its own frame
  int empty_w = camera_.width, empty_h = camera_.height;
  const auto fail = [&](const Refusal& why) {
    drops_.drop(why.reason, why.detail);
    publishEmpty(msg->header, empty_w, empty_h);
    reportFrame(msg->header, false, timer);
  };
  // Frames missing from the detector's stream, or whose depth never came (they never pair).
  countFrameGaps(frame_gaps_, drops_, msg->header.stamp, "detection");
  cv::Mat depth_m, instances;
  const Refusal depth_refused = readDepth(*depth_msg, depth_m);
  if (!depth_m.empty()) {
    empty_w = depth_m.cols;
    empty_h = depth_m.rows;
  }
  if (depth_refused) return fail(depth_refused);
  std::string err = uint16ToMat(msg->instance_image, instances);
  if (!err.empty()) return fail({"bad_instances", "instance image: " + err});
  if (instances.size() != depth_m.size())
    return fail({"size_mismatch", "instance image " + std::to_string(instances.cols) + "x" +
                                      std::to_string(instances.rows) + " differs from depth"});

  // Only detections of classes with object maps take part; unknown classes are bad input.
  std::vector<std::uint16_t> ids;
  std::vector<const semantic_exploration::Detection*> kept;
  std::unordered_set<std::uint16_t> listed, excluded;
  for (const auto& d : msg->detections) {
    listed.insert(d.instance_id);
    if (classes_.name(d.class_id).empty()) {
      drops_.drop("unknown_class", "class id " + std::to_string(d.class_id) + " ('" + d.class_name +
                                       "') is not in the class table");
      excluded.insert(d.instance_id);
    } else if (!d.class_name.empty() && d.class_name != classes_.name(d.class_id)) {
      // The detector and this node disagree on the class table: neither the id nor the name can be trusted.
      drops_.drop("class_mismatch", "instance " + std::to_string(d.instance_id) + ": class id " +
                                        std::to_string(d.class_id) + " is '" + classes_.name(d.class_id) +
                                        "' in the class table, but the detection names it '" + d.class_name + "'");
      excluded.insert(d.instance_id);
    } else if (!classes_.isOfInterest(d.class_id)) {
      excluded.insert(d.instance_id);
    } else {
      ids.push_back(d.instance_id);
      kept.push_back(&d);
    }
  }
  std::uint32_t unlisted = 0;
  for (int v = 0; v < instances.rows; ++v) {
    std::uint16_t* row = instances.ptr<std::uint16_t>(v);
    for (int u = 0; u < instances.cols; ++u) {
      if (!row[u]) continue;
      if (!listed.count(row[u])) ++unlisted;
      if (excluded.count(row[u])) row[u] = 0;
    }
  }
  if (unlisted) drops_.drop("unlisted_instance", std::to_string(unlisted) + " mask pixels of unlisted instance ids");

  Eigen::Isometry3d T_WC;
  if (const Refusal why = cameraPose(msg->header, T_WC)) return fail(why);

  semantic_exploration::RenderInstances srv;
  srv.request.pose = toPose(T_WC);
  if (have_info_) {
    srv.request.camera_info = camera_info_;
  } else {  // intrinsics from the parameters
    auto& ci = srv.request.camera_info;
    ci.width = static_cast<uint32_t>(camera_.width);
    ci.height = static_cast<uint32_t>(camera_.height);
    ci.K = {camera_.fx, 0.0, camera_.cx, 0.0, camera_.fy, camera_.cy, 0.0, 0.0, 1.0};
  }
  srv.request.camera_info.header = msg->header;
  srv.request.depth = *depth_msg;
  if (!callRender(srv)) return fail({"render_unavailable", "object_map/render_instances failed"});
  cv::Mat object_ids;
  err = uint16ToMat(srv.response.object_ids, object_ids);
  if (err.empty() && object_ids.size() != instances.size()) err = "size differs from the instance image";
  if (!err.empty()) return fail({"bad_render", "rendered object ids: " + err});

  cv::Mat cleaned;
  const semexp::MatchingOutput out = semexp::matchDetections(instances, ids, object_ids, config_, &cleaned);
  if (out.duplicate_ids) drops_.drop("duplicate_instance", std::to_string(out.duplicate_ids) + " repeated or zero instance ids");

  semantic_exploration::MatchedDetections matched;
  matched.header = msg->header;
  matched.instance_image = msg->instance_image;
  matched.instance_image.encoding = enc::TYPE_16UC1;
  matched.instance_image.step = static_cast<uint32_t>(cleaned.cols * 2);
  matched.instance_image.data.resize(static_cast<size_t>(cleaned.rows) * cleaned.cols * 2);
  for (int v = 0; v < cleaned.rows; ++v)
    std::memcpy(&matched.instance_image.data[static_cast<size_t>(v) * cleaned.cols * 2], cleaned.ptr(v),
                static_cast<size_t>(cleaned.cols) * 2);
  // out.detections follows `ids` except for repeated ids, which matchDetections skipped.
  std::unordered_set<std::uint16_t> emitted;
  size_t j = 0;
  for (const auto* d : kept) {
    if (!emitted.insert(d->instance_id).second || d->instance_id == 0) continue;
    const semexp::MatchResult& r = out.detections[j++];
    if (r.dropped) {
      ROS_DEBUG("instance_matching: dropped instance %u (%u px < %d)", r.instance_id, r.mask_pixels,
                config_.min_mask_pixels);
      continue;
    }
    semantic_exploration::MatchedDetection m;
    m.detection = *d;
    m.object_id = r.object_id;
    m.iou = r.iou;
    m.mask_pixels = r.mask_pixels;
    matched.detections.push_back(m);
  }
  matched_pub_.publish(matched);
  reportFrame(msg->header, true, timer);
}

}  // namespace semexp_ros
