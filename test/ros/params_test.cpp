// ROS parameter trees -> Config structs: types, required values, validation,
// all reported with the parameter's name.
#include <gtest/gtest.h>

#include "semantic_exploration/ros/params.hpp"
#include "semexp_test/config_errors.hpp"

using semexp_ros::ParamReader;
using XmlRpc::XmlRpcValue;

namespace {

XmlRpcValue cameraTree() {
  XmlRpcValue root;
  root["camera"]["width"] = 320;
  root["camera"]["height"] = 240;
  root["camera"]["fx"] = 262.5;
  root["camera"]["fy"] = 262.5;
  root["camera"]["cx"] = 159.5;
  root["camera"]["cy"] = 119.5;
  return root;
}

using semexp_test::rejected;

}  // namespace

TEST(Params, CameraLoadsAndIntegerFocalLengthIsANumber) {
  XmlRpcValue root = cameraTree();
  root["camera"]["fx"] = 300;  // an int where a double is expected is fine
  root["camera"]["d_max_m"] = 5.0;
  const auto cam = semexp_ros::loadCamera(ParamReader(root));
  EXPECT_DOUBLE_EQ(cam.fx, 300.0);
  EXPECT_DOUBLE_EQ(cam.d_max_m, 5.0);
  EXPECT_DOUBLE_EQ(cam.d_min_m, 0.1);  // default kept
}

TEST(Params, MissingIntrinsicsNameTheParameter) {
  XmlRpcValue root = cameraTree();
  root["camera"].clear();
  root["camera"]["width"] = 320;
  EXPECT_EQ(rejected([&] { semexp_ros::loadCamera(ParamReader(root)); }), "camera/height");
  XmlRpcValue empty;
  EXPECT_EQ(rejected([&] { semexp_ros::loadCamera(ParamReader(empty)); }), "camera/width");
}

TEST(Params, WrongTypeNamesTheParameter) {
  XmlRpcValue root = cameraTree();
  root["camera"]["fx"] = std::string("fast");
  EXPECT_EQ(rejected([&] { semexp_ros::loadCamera(ParamReader(root)); }), "camera/fx");
  XmlRpcValue p;
  p["planner"]["n_candidates"] = 2.5;
  EXPECT_EQ(rejected([&] { semexp_ros::loadPlanner(ParamReader(p)); }), "planner/n_candidates");
}

TEST(Params, ValidationRunsOnLoadedValues) {
  XmlRpcValue p;
  p["background_map"]["resolution_m"] = -0.04;
  EXPECT_EQ(rejected([&] { semexp_ros::loadBackgroundMap(ParamReader(p)); }), "background_map/resolution_m");
  XmlRpcValue w;
  w["planner"]["a_ent"] = 0.5;
  EXPECT_EQ(rejected([&] { semexp_ros::loadPlanner(ParamReader(w)); }), "planner/a_ent");
  XmlRpcValue e;
  e["exploration"]["d_obj_m"] = 3.5;
  EXPECT_EQ(rejected([&] { semexp_ros::loadExploration(ParamReader(e)); }), "exploration/d_obj_m");
  XmlRpcValue c;
  c["classes"]["of_interest"][0] = std::string("unicorn");
  EXPECT_EQ(rejected([&] { semexp_ros::loadClasses(ParamReader(c)); }), "classes/of_interest");
}

TEST(Params, ClassResolutionMapAndBounds) {
  XmlRpcValue p;
  p["classes"]["of_interest"][0] = std::string("chair");
  p["classes"]["of_interest"][1] = std::string("backpack");
  p["classes"]["resolution_m"]["backpack"] = 0.01;
  p["bounds"]["min_m"][0] = -1;
  p["bounds"]["min_m"][1] = -2.0;
  p["bounds"]["min_m"][2] = 0;
  p["bounds"]["max_m"][0] = 1;
  p["bounds"]["max_m"][1] = 2.0;
  p["bounds"]["max_m"][2] = 3;
  const ParamReader r(p);
  const auto t = semexp_ros::loadClasses(r);
  EXPECT_TRUE(t.isOfInterest(t.id("backpack")));
  EXPECT_DOUBLE_EQ(t.resolution(t.id("backpack")), 0.01);
  EXPECT_DOUBLE_EQ(t.resolution(t.id("chair")), t.default_resolution_m);  // map replaced as a whole
  const auto b = semexp_ros::loadBounds(r);
  EXPECT_DOUBLE_EQ(b.min_m.y(), -2.0);
  EXPECT_DOUBLE_EQ(b.max_m.z(), 3.0);
  XmlRpcValue bad;
  bad["bounds"]["min_m"][0] = 1.0;
  EXPECT_EQ(rejected([&] { semexp_ros::loadBounds(ParamReader(bad)); }), "bounds/min_m");
}

TEST(Params, TfSettingsDefaultsAndNames) {
  XmlRpcValue p;
  p["tf_timeout_s"] = 0.3;
  const auto t = semexp_ros::loadTf(ParamReader(p));
  EXPECT_DOUBLE_EQ(t.timeout_s, 0.3);
  EXPECT_DOUBLE_EQ(t.max_gap_s, 0.2);  // default
  p["max_tf_gap_s"] = -1.0;
  EXPECT_EQ(rejected([&] { semexp_ros::loadTf(ParamReader(p)); }), "max_tf_gap_s");
}

TEST(Params, AtLeastNamesTheParameterAndKeepsTheDefault) {
  XmlRpcValue p;
  p["tf_timeout_s"] = -0.5;
  p["background_map"]["colour_wait_s"] = 0.25;
  const ParamReader r(p);
  double v = 0.1;
  EXPECT_EQ(rejected([&] { r.getAtLeast("tf_timeout_s", v, 0.0, "s"); }), "tf_timeout_s");
  EXPECT_DOUBLE_EQ(v, 0.1);  // unchanged on error
  r.getAtLeast("background_map/colour_wait_s", v, 0.0, "s");
  EXPECT_DOUBLE_EQ(v, 0.25);
  double d = 3.0;
  r.getAtLeast("absent", d, 1.0, "");
  EXPECT_DOUBLE_EQ(d, 3.0);
}

TEST(Params, DetectorSectionLoadsAndChecksTheClassMap) {
  const semexp::ClassTable classes;  // chair, table, sofa, ...
  XmlRpcValue root;
  root["detector"]["model_path"] = std::string("/m.onnx");
  root["detector"]["input_size"][0] = 640;
  root["detector"]["input_size"][1] = 480;
  root["detector"]["conf_threshold"] = 0.4;
  root["detector"]["class_map"]["couch"] = std::string("sofa");
  root["detector"]["class_map"]["dining_table"] = std::string("table");
  root["detector"]["backend"] = std::string("opencv");
  const auto c = semexp_ros::loadDetector(ParamReader(root), classes);
  EXPECT_EQ(c.model_path, "/m.onnx");
  EXPECT_EQ(c.input_size[0], 640);
  EXPECT_EQ(c.input_size[1], 480);
  EXPECT_DOUBLE_EQ(c.conf_threshold, 0.4);
  EXPECT_DOUBLE_EQ(c.nms_iou, 0.45);  // default kept
  ASSERT_EQ(c.class_map.size(), 2u);  // replaces the default map
  EXPECT_EQ(c.class_map.at("couch"), "sofa");
  EXPECT_EQ(c.model_classes.size(), 80u);

  XmlRpcValue bad = root;
  bad["detector"]["class_map"]["couch"] = std::string("settee");  // not in classes/names
  EXPECT_EQ(rejected([&] { semexp_ros::loadDetector(ParamReader(bad), classes); }), "detector/class_map");
  bad = root;
  bad["detector"]["input_size"][2] = 3;
  EXPECT_EQ(rejected([&] { semexp_ros::loadDetector(ParamReader(bad), classes); }), "detector/input_size");
  bad = root;
  bad["detector"]["input_size"][0] = 640.5;
  EXPECT_EQ(rejected([&] { semexp_ros::loadDetector(ParamReader(bad), classes); }), "detector/input_size");
  bad = root;
  bad["detector"]["class_map"] = std::string("chair");
  EXPECT_EQ(rejected([&] { semexp_ros::loadDetector(ParamReader(bad), classes); }), "detector/class_map");
  bad = root;
  bad["detector"]["model_path"] = std::string("");
  EXPECT_EQ(rejected([&] { semexp_ros::loadDetector(ParamReader(bad), classes); }), "detector/model_path");
  bad = root;
  bad["detector"]["target"] = std::string("cuda");  // with backend opencv
  EXPECT_EQ(rejected([&] { semexp_ros::loadDetector(ParamReader(bad), classes); }), "detector/target");
}

TEST(Params, NodeConfigsLoadAndNameTheParameterAtFault) {
  XmlRpcValue root;
  root["background_map"]["frontier_period_s"] = 0.25;
  root["background_map"]["surface_share_period_s"] = 1.5;
  root["background_map"]["colour_wait_s"] = 0.1;
  root["background_map"]["start_free_radius_m"] = 0.75;
  root["background_map"]["restore_map_service"] = "";
  root["background_map"]["restore_wait_s"] = 1.5;
  root["depth_history"]["marker_period_s"] = 2.0;
  root["sync_max_interval_s"] = 0.03;
  const ParamReader p(root);
  const auto bg = semexp_ros::loadBackgroundMapNode(p);
  EXPECT_DOUBLE_EQ(bg.frontier_period_s, 0.25);
  EXPECT_DOUBLE_EQ(bg.surface_share_period_s, 1.5);
  EXPECT_DOUBLE_EQ(bg.colour_wait_s, 0.1);
  EXPECT_DOUBLE_EQ(bg.start_free_radius_m, 0.75);
  EXPECT_EQ(bg.restore_map_service, "");
  EXPECT_DOUBLE_EQ(bg.restore_wait_s, 1.5);
  EXPECT_DOUBLE_EQ(semexp_ros::loadDepthHistoryNode(p, semexp::DepthHistoryConfig()).marker_period_s, 2.0);
  EXPECT_DOUBLE_EQ(semexp_ros::loadImageSync(p).max_interval_s, 0.03);

  root["background_map"]["surface_share_period_s"] = -1.0;
  EXPECT_EQ(rejected([&] { semexp_ros::loadBackgroundMapNode(ParamReader(root)); }),
            "background_map/surface_share_period_s");
  root["background_map"]["surface_share_period_s"] = 61.0;
  EXPECT_EQ(rejected([&] { semexp_ros::loadBackgroundMapNode(ParamReader(root)); }),
            "background_map/surface_share_period_s");
  root["background_map"]["surface_share_period_s"] = 2.0;
  root["background_map"]["start_free_radius_m"] = -0.1;
  EXPECT_EQ(rejected([&] { semexp_ros::loadBackgroundMapNode(ParamReader(root)); }),
            "background_map/start_free_radius_m");
  root["background_map"]["start_free_radius_m"] = 0.5;
  root["background_map"]["restore_wait_s"] = -1.0;
  EXPECT_EQ(rejected([&] { semexp_ros::loadBackgroundMapNode(ParamReader(root)); }),
            "background_map/restore_wait_s");
  root["sync_max_interval_s"] = "fast";
  EXPECT_EQ(rejected([&] { semexp_ros::loadImageSync(ParamReader(root)); }), "sync_max_interval_s");
  // The history's image must be the planner's raycast size.
  root["planner"]["raycast_width"] = 24;
  EXPECT_EQ(rejected([&] { semexp_ros::loadDepthHistoryNode(ParamReader(root), semexp::DepthHistoryConfig()); }),
            "depth_history/width");
}

// The nested depth_noise block of object_map (the mesh's SDF error gate) loads by its full names.
TEST(Params, ObjectMapDepthNoiseLoadsAndNamesTheParameter) {
  XmlRpcValue root;
  root["object_map"]["mesh_max_sdf_std_m"] = 0.005;
  root["object_map"]["depth_noise"]["sigma_min_m"] = 0.01;
  root["object_map"]["depth_noise"]["s_per_m"] = 0.004;
  root["object_map"]["mesh_min_foreground"] = 0.6;
  root["object_map"]["save_tsdf"] = true;
  const auto om = semexp_ros::loadObjectMap(ParamReader(root));
  EXPECT_DOUBLE_EQ(om.mesh_min_foreground, 0.6);
  EXPECT_TRUE(om.save_tsdf);
  EXPECT_DOUBLE_EQ(om.mesh_max_sdf_std_m, 0.005);
  EXPECT_DOUBLE_EQ(om.depth_noise.sigma_min_m, 0.01);
  EXPECT_DOUBLE_EQ(om.depth_noise.s_per_m, 0.004);
  EXPECT_DOUBLE_EQ(om.depth_noise.sigma_max_m, 0.2);  // default kept
  EXPECT_DOUBLE_EQ(om.meshGate().max_sdf_std_m, 0.005);
  EXPECT_DOUBLE_EQ(om.meshGate().noise.sigma(2.0), 0.016);
  root["object_map"]["depth_noise"]["sigma_max_m"] = 0.001;
  EXPECT_EQ(rejected([&] { semexp_ros::loadObjectMap(ParamReader(root)); }), "object_map/depth_noise/sigma_max_m");
}

TEST(Params, RecordedReadsListEveryParameterWithItsDefault) {
  XmlRpcValue root = cameraTree();
  root["camera"]["d_max_m"] = 5.0;
  ParamReader p(root);
  std::vector<semexp_ros::ParamRead> reads;
  p.recordReads(&reads);
  semexp_ros::loadCamera(p);
  semexp_ros::loadBounds(p);
  ASSERT_EQ(reads.size(), 10u);  // width .. d_max_m, then bounds min_m and max_m
  EXPECT_EQ(reads[0].path, "camera/width");
  EXPECT_EQ(reads[0].default_text, "required");
  EXPECT_EQ(reads[6].path, "camera/d_min_m");
  EXPECT_EQ(reads[6].default_text, "0.10000000000000001");  // the default, not the value read
  EXPECT_EQ(reads[7].path, "camera/d_max_m");
  EXPECT_EQ(reads[7].default_text, "10");
  EXPECT_EQ(reads[8].path, "bounds/min_m");
  EXPECT_EQ(reads[8].default_text, "[-10, -10, -0.5]");
  p.recordReads(nullptr);
  semexp_ros::loadExploration(p);
  EXPECT_EQ(reads.size(), 10u);
}
