#include "semantic_exploration/ros/detector_node.hpp"

#include <sensor_msgs/image_encodings.h>

#include "semantic_exploration/Detections.h"
#include "semantic_exploration/core/camera.hpp"

namespace semexp_ros {

DetectorNode::DetectorNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) {
  const auto p = ParamReader::fromNodeHandle(pnh);
  classes_ = loadClasses(p);
  const semexp::PinholeCamera camera = loadCamera(p);
  out_size_ = cv::Size(camera.width, camera.height);
  segmenter_ = std::make_unique<semexp::InstanceSegmenter>(loadDetector(p, classes_));
  detections_pub_ = nh.advertise<semantic_exploration::Detections>("detections", 5);
  info_sub_ = nh.subscribe("camera/camera_info", 1, &DetectorNode::infoCallback, this);
  // Queue of one: while a frame is being segmented only the newest waits.
  colour_sub_ = nh.subscribe("camera/rgb/image_raw", 1, &DetectorNode::colourCallback, this);
  const auto& c = segmenter_->config();
  ROS_INFO("detector: %s, input %dx%d, %d candidates, %zu of %zu model classes mapped, %s/%s", c.model_path.c_str(),
           c.input_size[0], c.input_size[1], segmenter_->numCandidates(), c.class_map.size(), c.model_classes.size(),
           c.backend.c_str(), c.target.c_str());
  last_log_ = ros::WallTime::now();
}

void DetectorNode::infoCallback(const sensor_msgs::CameraInfoConstPtr& msg) {
  if (msg->width == 0 || msg->height == 0) {
    drops_.drop("bad_camera_info", "camera_info of size 0");
    return;
  }
  // The instance image is allocated at this size for every frame: 100000 x 100000 px would be 20 GB.
  if (const std::string big = semexp::PinholeCamera::checkSize(msg->width, msg->height); !big.empty()) {
    drops_.drop("bad_camera_info", "camera_info size " + big + "; keeping " + std::to_string(out_size_.width) +
                                       " x " + std::to_string(out_size_.height));
    return;
  }
  out_size_ = cv::Size(static_cast<int>(msg->width), static_cast<int>(msg->height));
}

void DetectorNode::colourCallback(const sensor_msgs::ImageConstPtr& msg) {
  cv::Mat rgb;
  const std::string err = colourToRgb(*msg, rgb);
  if (!err.empty()) {
    drops_.drop("bad_colour", err);
    return;
  }
  semexp::InstanceImage result;
  semexp::DetectorTiming t;
  try {
    result = segmenter_->segment(rgb, out_size_, &t);
  } catch (const std::exception& e) {  // cv::Exception included: the frame is lost, the node goes on
    drops_.drop("inference_failed", e.what());
    return;
  }
  semantic_exploration::Detections out;
  out.header = msg->header;
  out.instance_image = toImageMsg(msg->header, result.ids);
  for (const auto& e : result.entries) {
    semantic_exploration::Detection d;
    d.instance_id = e.instance_id;
    d.class_id = static_cast<uint16_t>(classes_.id(e.class_name));
    d.class_name = e.class_name;
    d.confidence = e.confidence;
    d.pixel_count = e.pixel_count;
    out.detections.push_back(d);
  }
  detections_pub_.publish(out);

  ++frames_;
  ++frames_since_log_;
  sum_.preprocess_ms += t.preprocess_ms;
  sum_.inference_ms += t.inference_ms;
  sum_.decode_ms += t.decode_ms;
  if ((ros::WallTime::now() - last_log_).toSec() >= 30.0) {
    const double n = static_cast<double>(frames_since_log_);
    ROS_INFO("detector: %lu frames; last %.0f s: %.1f Hz, per frame %.1f ms pre-processing, %.1f ms inference, "
             "%.1f ms decoding", static_cast<unsigned long>(frames_), (ros::WallTime::now() - last_log_).toSec(),
             n / (ros::WallTime::now() - last_log_).toSec(), sum_.preprocess_ms / n, sum_.inference_ms / n,
             sum_.decode_ms / n);
    sum_ = semexp::DetectorTiming();
    frames_since_log_ = 0;
    last_log_ = ros::WallTime::now();
  }
}

}  // namespace semexp_ros
