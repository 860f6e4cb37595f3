#include "semantic_exploration/ros/display_cut_node.hpp"

#include "semantic_exploration/ros/conversions.hpp"
#include "semantic_exploration/ros/params.hpp"

namespace semexp_ros {

DisplayCutNode::DisplayCutNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : nh_(nh) {
  max_z_m_ = loadDisplayCut(ParamReader::fromNodeHandle(pnh));
  const char* names[2][2] = {{"background_map/occupied", "occupied"}, {"background_map/frontiers", "frontiers"}};
  for (int i = 0; i < 2; ++i) {
    Relay& r = relays_[i];
    r.from = names[i][0];
    const auto status = [this, &r](const ros::SingleSubscriberPublisher&) { update(r); };
    r.pub = pnh.advertise<sensor_msgs::PointCloud2>(names[i][1], 1, status, status, ros::VoidConstPtr(), true);
  }
  ROS_INFO("display_cut: %s and %s without points above z = %.2f m", relays_[0].pub.getTopic().c_str(),
           relays_[1].pub.getTopic().c_str(), max_z_m_);
}

void DisplayCutNode::update(Relay& r) {
  if (r.pub.getNumSubscribers() > 0 && !r.sub) {
    const boost::function<void(const sensor_msgs::PointCloud2ConstPtr&)> cb =
        [this, &r](const sensor_msgs::PointCloud2ConstPtr& msg) { cloud(r, msg); };
    r.sub = nh_.subscribe<sensor_msgs::PointCloud2>(r.from, 1, cb);
  } else if (r.pub.getNumSubscribers() == 0 && r.sub) {
    r.sub.shutdown();
  }
}

void DisplayCutNode::cloud(Relay& r, const sensor_msgs::PointCloud2ConstPtr& msg) {
  sensor_msgs::PointCloud2 out;
  const std::string bad = cutCloudAboveZ(*msg, max_z_m_, out);
  if (!bad.empty()) {
    drops_.drop("bad_cloud", "display_cut: " + r.from + ": " + bad);
    return;
  }
  r.pub.publish(out);
}

}  // namespace semexp_ros
