#include "semantic_exploration/ros/object_map_node.hpp"

#include <sensor_msgs/image_encodings.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <cstring>

#include "semantic_exploration/ObjectArray.h"
#include "semantic_exploration/ros/conversions.hpp"

namespace semexp_ros {

namespace {

/// A distinct, stable colour per class (hue steps of the golden angle).
std_msgs::ColorRGBA classColour(int class_id) {
  const double h = std::fmod(class_id * 0.618033988749895, 1.0) * 6.0;
  const double x = 1.0 - std::abs(std::fmod(h, 2.0) - 1.0);
  double r = 0, g = 0, b = 0;
  switch (static_cast<int>(h)) {
    case 0: r = 1, g = x; break;
    case 1: r = x, g = 1; break;
    case 2: g = 1, b = x; break;
    case 3: g = x, b = 1; break;
    case 4: r = x, b = 1; break;
    default: r = 1, b = x; break;
  }
  std_msgs::ColorRGBA c;
  c.r = static_cast<float>(0.2 + 0.8 * r);
  c.g = static_cast<float>(0.2 + 0.8 * g);
  c.b = static_cast<float>(0.2 + 0.8 * b);
  c.a = 1.f;
  return c;
}

/// The 12 edges of an axis-aligned box as LINE_LIST points.
void boxEdges(const geometry_msgs::Point& lo, const geometry_msgs::Point& hi, std::vector<geometry_msgs::Point>& out) {
  const auto corner = [&](int i) {
    geometry_msgs::Point p;
    p.x = (i & 1) ? hi.x : lo.x;
    p.y = (i & 2) ? hi.y : lo.y;
    p.z = (i & 4) ? hi.z : lo.z;
    return p;
  };
  for (int i = 0; i < 8; ++i)
    for (int axis = 1; axis < 8; axis <<= 1)
      if (!(i & axis)) {
        out.push_back(corner(i));
        out.push_back(corner(i | axis));
      }
}

}  // namespace

ObjectMapNode::ObjectMapNode(ros::NodeHandle& nh, ros::NodeHandle& pnh)
    : CameraNode(nh, pnh, BeforeCameraInfo::kUseParameters, true) {
  const auto& p = params();
  config_ = loadObjectMap(p);
  classes_ = loadClasses(p);
  exploration_ = loadExploration(p);
  map_ = std::make_unique<semexp::ObjectMap>(config_, classes_);
  summaries_ = std::make_unique<semexp::ObjectSummaryCache>(exploration_.d_obj_m);
  // The maps must hold what a camera inside the bounds sees (it is refused outside them).
  if (const std::string why = map_->checkBounds(bounds_, camera_.d_max_m); !why.empty())
    throw semexp::ConfigError("bounds/max_m", why);
  if (const std::string why = map_->checkIntegratedDepth(exploration_.d_bg_m); !why.empty())
    throw semexp::ConfigError("object_map/behind_surface_quadratic_per_m", why);

  objects_pub_ = pnh.advertise<semantic_exploration::ObjectArray>("objects", 1, true);
  meshes_pub_ = pnh.advertise<visualization_msgs::MarkerArray>("meshes", 1, true);
  render_srv_ = pnh.advertiseService("render_instances", &ObjectMapNode::renderInstances, this);
  gains_srv_ = pnh.advertiseService("compute_gains", &ObjectMapNode::computeGains, this);
  save_srv_ = pnh.advertiseService("save", &ObjectMapNode::save, this);
  matched_sub_.subscribe(nh, "matched_detections", 5);
  depth_sub_.subscribe(nh, "camera/depth/image_raw", 5);
  rgb_sub_.subscribe(nh, "camera/rgb/image_raw", 5);
  sync_ = makeSync<SyncPolicy>(loadImageSync(p).max_interval_s, matched_sub_, depth_sub_, rgb_sub_);
  sync_->registerCallback(&ObjectMapNode::frameCallback, this);
  std::string interest;
  for (const auto& c : classes_.of_interest) interest += (interest.empty() ? "" : ", ") + c;
  // Objects live only in memory: after a restart (respawn) the map starts
  // empty and finds them again; say so, so a run's log shows what happened.
  ROS_INFO("object_map: classes of interest [%s], truncation %.1f voxels; starting with no objects "
           "(objects from before a restart are not restored: they are rebuilt from new observations)",
           interest.c_str(), config_.truncation_voxels);
}

void ObjectMapNode::frameCallback(const semantic_exploration::MatchedDetectionsConstPtr& matched,
                                  const sensor_msgs::ImageConstPtr& depth_msg,
                                  const sensor_msgs::ImageConstPtr& rgb_msg) {
  const FrameTimer timer;
  const auto fail = [&](const Refusal& why) {
    // The (unchanged) objects go out for a refused frame too, stamped with it: a listener that waits for the
    // objects of a frame it knows was handled (the planner's plan_once in deterministic runs) gets them.
    if (matched->header.stamp > last_published_stamp_ &&
        (ros::WallTime::now() - last_publish_).toSec() >= config_.publish_period_s)
      publishObjects(matched->header.stamp);
    refuse(matched->header, why, timer);
  };
  cv::Mat depth_m, rgb, instances;
  if (const Refusal why = readDepth(*depth_msg, depth_m)) return fail(why);
  std::string err = colourToRgb(*rgb_msg, rgb);
  if (!err.empty()) return fail({"bad_rgb", err});
  if (rgb.size() != depth_m.size()) return fail({"size_mismatch", "colour and depth differ in size"});
  err = uint16ToMat(matched->instance_image, instances);
  if (!err.empty()) return fail({"bad_instances", "instance image: " + err});
  if (instances.size() != depth_m.size()) return fail({"size_mismatch", "instance image differs from depth in size"});

  Eigen::Isometry3d T_WC;
  if (const Refusal why = cameraPose(matched->header, T_WC)) return fail(why);

  std::vector<semexp::ObjectDetection> detections;
  for (const auto& d : matched->detections)
    detections.push_back({d.detection.instance_id, d.object_id, static_cast<int>(d.detection.class_id)});
  semexp::FrameIntegration r;
  try {
    const bool reuse = !cached_render_.ids.empty() && cached_render_.stamp == matched->header.stamp &&
                       cached_render_.version == map_->version() && cached_render_.ids.size() == depth_m.size();
    r = map_->integrateFrame(camera_, T_WC, depth_m, rgb, instances, detections, reuse ? &cached_render_.ids : nullptr);
    cached_render_.ids.release();
  } catch (const std::exception& e) {
    return fail({"integration_error", e.what()});
  }
  if (r.dropped_unknown_class) drops_.drop("unknown_class", std::to_string(r.dropped_unknown_class) + " detection(s)");
  if (r.dropped_unknown_object)
    drops_.drop("unknown_object", std::to_string(r.dropped_unknown_object) + " detection(s) matched to no known object");
  if (r.dropped_full)
    drops_.drop("too_many_objects", "no free object id: 65535 objects exist or were merged in the last " +
                                         std::to_string(semexp::ObjectIdPool::kReuseAfterFrames) + " frames");
  for (const auto id : r.created)
    ROS_INFO("object_map: new object %u (%s)", id, map_->object(id)->class_name.c_str());
  for (size_t i = 0; i < r.merged.size(); ++i)
    ROS_INFO("object_map: object %u is part of object %u (%s): merged", r.merged[i].first, r.merged[i].second,
             i < r.merge_reasons.size() ? r.merge_reasons[i].c_str() : "");
  for (const auto& s : r.split)
    ROS_INFO("object_map: object %u split off object %u (two detections of it lay apart)", s.first, s.second);
  last_stamp_ = matched->header.stamp;
  // Said again at the first frame: the start-up line goes out before any
  // /rosout subscriber has connected to a respawned node, so it can be lost.
  if (!integrated_any_)
    ROS_INFO("object_map: first frame since start integrated with %zu object(s); objects are rebuilt from new "
             "observations", map_->objects().size());
  integrated_any_ = true;
  // Objects before the report: whoever waits for the report (lockstep) then has this frame's objects.
  if ((ros::WallTime::now() - last_publish_).toSec() >= config_.publish_period_s) publishObjects(last_stamp_);
  reportFrame(matched->header, true, timer);
}

void ObjectMapNode::publishObjects(const ros::Time& stamp) {
  last_publish_ = ros::WallTime::now();
  last_published_stamp_ = std::max(last_published_stamp_, stamp);
  semantic_exploration::ObjectArray arr;
  arr.header.stamp = stamp;
  arr.header.frame_id = frames_.world;
  visualization_msgs::MarkerArray markers;
  const bool draw = meshes_pub_.getNumSubscribers() > 0;
  const auto marker = [&](const char* ns, std::uint32_t id, int type) {
    visualization_msgs::Marker m;
    m.header = arr.header;
    m.ns = ns;
    m.id = static_cast<int>(id);
    m.type = type;
    m.action = visualization_msgs::Marker::ADD;
    m.pose.orientation.w = 1.0;
    m.scale.x = m.scale.y = m.scale.z = 1.0;
    return m;
  };
  if (draw) {
    // Objects merged into others since the last publication: take their markers down.
    for (const auto id : marker_ids_) {
      if (map_->object(id)) continue;
      for (const char* ns : {"object_meshes", "object_boxes", "object_labels"}) {
        visualization_msgs::Marker m = marker(ns, id, visualization_msgs::Marker::TRIANGLE_LIST);
        m.action = visualization_msgs::Marker::DELETE;
        markers.markers.push_back(m);
      }
    }
    marker_ids_.clear();
  }
  summaries_->prune(*map_);  // objects merged away since
  for (const auto& kv : map_->objects()) {
    const semexp::MappedObject& o = *kv.second;
    const semexp::TsdfSummary& s = summaries_->get(*map_, o);
    const semantic_exploration::ObjectInfo info = toObjectInfo(o, s);
    arr.objects.push_back(info);
    if (!draw) continue;
    marker_ids_.insert(o.id);
    // Box and label of the surface (both taken down while the object has no surface voxel yet).
    const int surface_action = s.voxel_count > 0 ? visualization_msgs::Marker::ADD : visualization_msgs::Marker::DELETE;
    visualization_msgs::Marker box = marker("object_boxes", o.id, visualization_msgs::Marker::LINE_LIST);
    box.action = surface_action;
    box.scale.x = 0.01;  // line width, m
    box.color = classColour(o.class_id);
    if (s.voxel_count > 0) boxEdges(info.bbox_min, info.bbox_max, box.points);
    markers.markers.push_back(box);
    visualization_msgs::Marker label = marker("object_labels", o.id, visualization_msgs::Marker::TEXT_VIEW_FACING);
    label.action = surface_action;
    label.text = o.class_name + " #" + std::to_string(o.id);
    label.pose.position.x = 0.5 * (info.bbox_min.x + info.bbox_max.x);
    label.pose.position.y = 0.5 * (info.bbox_min.y + info.bbox_max.y);
    label.pose.position.z = info.bbox_max.z + 0.1;  // above the box, m
    label.scale.z = 0.12;                           // text height, m
    label.color = classColour(o.class_id);
    markers.markers.push_back(label);
    const semexp::Mesh mesh = map_->mesh(o);
    visualization_msgs::Marker m = marker("object_meshes", o.id, visualization_msgs::Marker::TRIANGLE_LIST);
    m.action = mesh.empty() ? visualization_msgs::Marker::DELETE : visualization_msgs::Marker::ADD;
    m.color.r = m.color.g = m.color.b = m.color.a = 1.0;
    for (const auto& t : mesh.triangles)
      for (int k = 0; k < 3; ++k) {
        m.points.push_back(toPoint(mesh.vertices_W[t[k]].cast<double>()));
        std_msgs::ColorRGBA c;
        c.r = mesh.colours[t[k]][0] / 255.f;
        c.g = mesh.colours[t[k]][1] / 255.f;
        c.b = mesh.colours[t[k]][2] / 255.f;
        c.a = 1.f;
        m.colors.push_back(c);
      }
    markers.markers.push_back(m);
  }
  objects_pub_.publish(arr);
  if (!markers.markers.empty()) meshes_pub_.publish(markers);
}

bool ObjectMapNode::renderInstances(semantic_exploration::RenderInstances::Request& req,
                                    semantic_exploration::RenderInstances::Response& res) {
  // instance_matching asks for the render of the frame this node integrates next: the render is part of that
  // frame's cost, not of instance_matching's (whose thread only waits for the answer).
  const FrameTimer timer;
  const bool answered = answerRender(req, res);
  chargeCpu(timer.cpu_ms());
  return answered;
}

bool ObjectMapNode::answerRender(semantic_exploration::RenderInstances::Request& req,
                                 semantic_exploration::RenderInstances::Response& res) {
  // Refused before anything is sized from it: the render and its answer take w x h per-pixel buffers.
  if (const std::string big = semexp::PinholeCamera::checkSize(req.camera_info.width, req.camera_info.height);
      !big.empty()) {
    drops_.drop("request_too_large", "render_instances: camera_info " + big);
    return false;
  }
  semexp::PinholeCamera cam;
  std::string err = cameraFromInfo(req.camera_info, camera_.d_min_m, camera_.d_max_m, cam);
  if (!err.empty()) {
    drops_.drop("bad_render_request", err);
    return false;
  }
  Eigen::Isometry3d T_WC;
  err = fromPose(req.pose, T_WC);
  if (!err.empty()) {
    drops_.drop("bad_render_request", err);
    return false;
  }
  if (!bounds_.contains(T_WC.translation())) {
    drops_.drop("out_of_bounds", "render_instances: " + outOfBounds("camera", T_WC.translation()));
    return false;
  }
  cv::Mat depth_m;
  if (!req.depth.data.empty()) {
    err = depthToMeters(req.depth, depth_m);
    if (err.empty() && (depth_m.cols != cam.width || depth_m.rows != cam.height))
      err = "depth size differs from camera_info";
    if (!err.empty()) {
      drops_.drop("bad_render_request", err);
      return false;
    }
  }
  cv::Mat ids;
  map_->render(cam, T_WC, depth_m, ids);
  if (!req.depth.data.empty() && cam.width == camera_.width && cam.height == camera_.height) {
    cached_render_.stamp = req.depth.header.stamp;
    cached_render_.version = map_->version();
    cached_render_.ids = ids;
  }
  std_msgs::Header header;
  header.stamp = req.depth.header.stamp;
  header.frame_id = req.camera_info.header.frame_id.empty() ? frames_.camera : req.camera_info.header.frame_id;
  res.object_ids = toImageMsg(header, ids);
  for (const auto id : semexp::ObjectMap::visibleIds(ids)) res.visible_object_ids.push_back(id);
  return true;
}

bool ObjectMapNode::computeGains(semantic_exploration::ComputeGains::Request& req,
                                 semantic_exploration::ComputeGains::Response& res) {
  const std::string why = semexp::SphericalGrid::checkRequest(static_cast<long>(req.positions.size()), req.width,
                                                              req.height);
  if (!why.empty()) {
    drops_.drop(req.width > 0 && req.height > 0 ? "request_too_large" : "bad_gain_request", "compute_gains: " + why);
    return false;
  }
  semexp::SphericalGrid grid;
  grid.width = req.width;
  grid.height = req.height;
  grid.vfov_rad = camera_.vfov_rad();
  const std::vector<Eigen::Vector3d> positions = fromPoints(req.positions);
  for (const auto& p_W : positions)
    if (!bounds_.contains(p_W)) {
      drops_.drop("out_of_bounds", "compute_gains: " + outOfBounds("position", p_W));
      return false;
    }
  std::vector<cv::Mat> gains, hits;
  try {
    map_->computeGains(positions, grid, req.max_depth_m, exploration_.d_obj_m, camera_.d_max_m, gains, hits);
  } catch (const std::exception& e) {
    drops_.drop("bad_gain_request", e.what());
    return false;
  }
  std_msgs::Header header;
  header.stamp = last_stamp_;
  header.frame_id = frames_.world;
  for (size_t i = 0; i < gains.size(); ++i) {
    res.distance_gain.push_back(toImageMsg(header, gains[i]));
    res.hit_depth.push_back(toImageMsg(header, hits[i]));
  }
  return true;  // entropy_gain stays empty: object maps hold no entropy
}

bool ObjectMapNode::save(semantic_exploration::SaveMap::Request& req, semantic_exploration::SaveMap::Response& res) {
  if (saveRefused(req.directory, res)) return true;
  std::string error;
  res.files = map_->save(req.directory, exploration_.d_obj_m, &error);
  res.success = error.empty();
  res.message = error.empty() ? "object_map: wrote " + std::to_string(res.files.size()) + " files (" +
                                    std::to_string(map_->objects().size()) + " objects) to " + req.directory
                              : "object_map: " + error;
  if (!res.success) ROS_ERROR("%s", res.message.c_str());
  return true;
}

}  // namespace semexp_ros
