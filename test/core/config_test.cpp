// Every Config::validate() accepts the paper's defaults and rejects bad values
// naming the parameter.
#include <gtest/gtest.h>

#include <limits>

#include "semantic_exploration/core/background_map_config.hpp"
#include "semantic_exploration/core/bounds.hpp"
#include "semantic_exploration/core/camera.hpp"
#include "semantic_exploration/core/class_table.hpp"
#include "semantic_exploration/core/depth_history_config.hpp"
#include "semantic_exploration/core/exploration_config.hpp"
#include "semantic_exploration/core/matching_config.hpp"
#include "semantic_exploration/core/object_map_config.hpp"
#include "semantic_exploration/core/planner_config.hpp"
#include "semexp_test/config_errors.hpp"

using namespace semexp;

using semexp_test::rejected;

TEST(Config, DefaultsAreValidAndMatchTableI) {
  PinholeCamera cam;
  EXPECT_EQ(rejected([&] { cam.validate(); }), "");
  EXPECT_EQ(cam.width, 320);
  EXPECT_EQ(cam.height, 240);
  EXPECT_DOUBLE_EQ(cam.fx, 262.5);
  EXPECT_DOUBLE_EQ(cam.d_min_m, 0.1);
  EXPECT_DOUBLE_EQ(cam.d_max_m, 10.0);
  BackgroundMapConfig bg;
  EXPECT_EQ(rejected([&] { bg.validate(); }), "");
  EXPECT_DOUBLE_EQ(bg.resolution_m, 0.04);
  PlannerConfig pl;
  EXPECT_EQ(rejected([&] { pl.validate(); }), "");
  EXPECT_EQ(pl.n_candidates, 20);
  EXPECT_DOUBLE_EQ(pl.p_frontier, 0.5);
  EXPECT_DOUBLE_EQ(pl.v_max_mps, 1.5);
  EXPECT_DOUBLE_EQ(pl.omega_max_radps, 0.75);
  EXPECT_DOUBLE_EQ(pl.mav_radius_m, 0.125);
  EXPECT_EQ(pl.raycast_width, 36);
  EXPECT_EQ(pl.raycast_height, 10);
  ExplorationConfig ex;
  EXPECT_EQ(rejected([&] { ex.validate(); }), "");
  EXPECT_DOUBLE_EQ(ex.d_bg_m, 3.0);
  EXPECT_DOUBLE_EQ(ex.d_obj_m, 1.0);
  ClassTable ct;
  EXPECT_EQ(rejected([&] { ct.validate(); }), "");
  EXPECT_DOUBLE_EQ(ct.resolution(ct.id("chair")), 0.02);
  EXPECT_EQ(rejected([] { ObjectMapConfig().validate(); }), "");
  EXPECT_EQ(rejected([] { MatchingConfig().validate(); }), "");
  EXPECT_EQ(rejected([] { DepthHistoryConfig().validate(); }), "");
  EXPECT_EQ(rejected([] { Bounds().validate(); }), "");
}

TEST(Config, NegativeResolutionIsRejected) {
  BackgroundMapConfig bg;
  bg.resolution_m = -0.04;
  EXPECT_EQ(rejected([&] { bg.validate(); }), "background_map/resolution_m");
  ClassTable ct;
  ct.resolution_m["chair"] = -0.02;
  EXPECT_EQ(rejected([&] { ct.validate(); }), "classes/resolution_m");
}

TEST(Config, WeightsMustSumToOne) {
  PlannerConfig pl;
  pl.a_ent = 0.5;  // 0.5 + 0.33 + 0.33 = 1.16
  EXPECT_EQ(rejected([&] { pl.validate(); }), "planner/a_ent");
  pl.a_ent = 1.0;
  pl.a_bg = pl.a_obj = 0.0;  // classic mode
  EXPECT_EQ(rejected([&] { pl.validate(); }), "");
}

TEST(Config, RoomSearchRadiusIsBounded) {
  PlannerConfig pl;
  for (double r : {-0.1, 5.5, std::numeric_limits<double>::quiet_NaN()}) {
    pl.room_search_radius_m = r;
    EXPECT_EQ(rejected([&] { pl.validate(); }), "planner/room_search_radius_m") << r;
  }
  pl.room_search_radius_m = 0.0;  // off
  EXPECT_EQ(rejected([&] { pl.validate(); }), "");
}

TEST(Config, ObjectDistanceMustBeBelowBackgroundDistance) {
  ExplorationConfig ex;
  ex.d_obj_m = 3.0;
  EXPECT_EQ(rejected([&] { ex.validate(); }), "exploration/d_obj_m");
  ex.d_obj_m = 4.0;
  EXPECT_EQ(rejected([&] { ex.validate(); }), "exploration/d_obj_m");
}

TEST(Config, UnknownClassIsRejected) {
  ClassTable ct;
  ct.of_interest = {"chair", "unicorn"};
  EXPECT_EQ(rejected([&] { ct.validate(); }), "classes/of_interest");
  ct.of_interest = {"chair"};
  ct.resolution_m["dragon"] = 0.02;
  EXPECT_EQ(rejected([&] { ct.validate(); }), "classes/resolution_m");
}

TEST(Config, MissingOrBadIntrinsicsAreRejected) {
  PinholeCamera cam;
  cam.fx = 0;  // what an unset intrinsic reads as
  EXPECT_EQ(rejected([&] { cam.validate(); }), "camera/fx");
  cam = PinholeCamera();
  cam.width = 0;
  EXPECT_EQ(rejected([&] { cam.validate(); }), "camera/width");
  cam = PinholeCamera();
  cam.cy = 500;
  EXPECT_EQ(rejected([&] { cam.validate(); }), "camera/cy");
  cam = PinholeCamera();
  cam.d_max_m = 0.05;
  EXPECT_EQ(rejected([&] { cam.validate(); }), "camera/d_max_m");
}

TEST(Config, RaycastsMustFitOneGainRequest) {
  semexp::PlannerConfig p;
  p.raycast_width = 360;
  p.raycast_height = 180;  // one image fits, 20 of them (1.3 M rays) do not
  EXPECT_EQ(rejected([&] { p.validate(); }), "planner/raycast_width");
  p.n_candidates = 4;
  // The object candidates' ring views go in one request too: 4 x 8 images of 64,800 rays do not fit, 4 x 1 do.
  EXPECT_EQ(rejected([&] { p.validate(); }), "planner/object_view_samples");
  p.p_frontier = 1.0;  // classic: no object is sampled, so no ring is evaluated
  EXPECT_EQ(rejected([&] { p.validate(); }), "");
  p.p_frontier = 0.5;
  p.object_view_samples = 1;
  EXPECT_EQ(rejected([&] { p.validate(); }), "");
  p.object_view_samples = 0;
  EXPECT_EQ(rejected([&] { p.validate(); }), "planner/object_view_samples");
  semexp::DepthHistoryConfig h;
  h.width = 720;
  h.height = 180;
  EXPECT_EQ(rejected([&] { h.validate(); }), "depth_history/width");
}

TEST(Config, CameraSizeIsCapped) {
  EXPECT_EQ(PinholeCamera::checkSize(320, 240), "");
  EXPECT_EQ(PinholeCamera::checkSize(4096, 4096), "");
  EXPECT_EQ(PinholeCamera::checkSize(20000, 20000),
            "must be <= 8192 px a side (PinholeCamera::kMaxSidePx), got 20000 x 20000");
  EXPECT_EQ(PinholeCamera::checkSize(8192, 4096),
            "width x height must be <= 16777216 px (PinholeCamera::kMaxPixels), got 8192 x 4096");
  PinholeCamera cam;
  cam.height = 10000;
  cam.cy = 4999.5;
  EXPECT_EQ(rejected([&] { cam.validate(); }), "camera/height");
  cam = PinholeCamera();
  cam.width = 10000;
  cam.cx = 4999.5;
  EXPECT_EQ(rejected([&] { cam.validate(); }), "camera/width");
}

TEST(Config, OtherBadValues) {
  PlannerConfig pl;
  pl.p_frontier = 1.5;
  EXPECT_EQ(rejected([&] { pl.validate(); }), "planner/p_frontier");
  BackgroundMapConfig bg;
  bg.block_size = 6;
  EXPECT_EQ(rejected([&] { bg.validate(); }), "background_map/block_size");
  MatchingConfig m;
  m.iou_threshold = 0;
  EXPECT_EQ(rejected([&] { m.validate(); }), "matching/iou_threshold");
  ObjectMapConfig om;
  om.foreground_border_px = 65;
  EXPECT_EQ(rejected([&] { om.validate(); }), "object_map/foreground_border_px");
  om = ObjectMapConfig();
  om.full_weight_depth_m = -0.5;
  EXPECT_EQ(rejected([&] { om.validate(); }), "object_map/full_weight_depth_m");
  om = ObjectMapConfig();
  om.piece_max_distance_m = 0.0;
  EXPECT_EQ(rejected([&] { om.validate(); }), "object_map/piece_max_distance_m");
  om = ObjectMapConfig();
  om.foreground_prior = 1.2;
  EXPECT_EQ(rejected([&] { om.validate(); }), "object_map/foreground_prior");
  om = ObjectMapConfig();
  om.foreground_prior = 0.3;
  om.foreground_prior_weight = 2.0;  // 2 * (0.5 - 0.3) = 0.4: one detection lifts a voxel to 0.533
  EXPECT_NO_THROW(om.validate());
  om.foreground_prior_weight = 2.5;  // 0.5: one detection leaves it at 0.5, so no new object has a surface
  EXPECT_EQ(rejected([&] { om.validate(); }), "object_map/foreground_prior_weight");
  om = ObjectMapConfig();
  om.mesh_min_weight = -1.0;
  EXPECT_EQ(rejected([&] { om.validate(); }), "object_map/mesh_min_weight");
  om.mesh_min_weight = 4.0;
  om.max_weight = 3.0;  // no voxel could ever reach the minimum: every mesh would stay empty
  EXPECT_EQ(rejected([&] { om.validate(); }), "object_map/mesh_min_weight");
  om = ObjectMapConfig();
  om.mesh_max_sdf_std_m = -0.001;
  EXPECT_EQ(rejected([&] { om.validate(); }), "object_map/mesh_max_sdf_std_m");
  om = ObjectMapConfig();
  om.mesh_max_sdf_std_m = 0.0004;  // under sigma_min_m / sqrt(max_weight) = 0.5 mm: no voxel could ever pass
  EXPECT_EQ(rejected([&] { om.validate(); }), "object_map/mesh_max_sdf_std_m");
  om.mesh_max_sdf_std_m = 0.0005;
  EXPECT_NO_THROW(om.validate());
  om = ObjectMapConfig();
  for (const double p : {0.49, 1.0, std::nan("")}) {  // under the paper's 0.5, or a bound no mean can exceed
    om.mesh_min_foreground = p;
    EXPECT_EQ(rejected([&] { om.validate(); }), "object_map/mesh_min_foreground") << p;
  }
  om.mesh_min_foreground = 0.6;
  EXPECT_NO_THROW(om.validate());
  EXPECT_FLOAT_EQ(om.meshGate().min_foreground, 0.6f);
  EXPECT_FLOAT_EQ(ObjectMapConfig().meshGate().min_foreground, 0.5f);  // the paper's extraction by default
  om = ObjectMapConfig();
  om.depth_noise.sigma_min_m = 0.0;
  EXPECT_EQ(rejected([&] { om.validate(); }), "object_map/depth_noise/sigma_min_m");
  om = ObjectMapConfig();
  om.depth_noise.s_per_m = -0.002;
  EXPECT_EQ(rejected([&] { om.validate(); }), "object_map/depth_noise/s_per_m");
  om = ObjectMapConfig();
  om.depth_noise.sigma_max_m = 0.001;  // under sigma_min_m
  EXPECT_EQ(rejected([&] { om.validate(); }), "object_map/depth_noise/sigma_max_m");
  Bounds b;
  b.max_m.z() = b.min_m.z();
  EXPECT_EQ(rejected([&] { b.validate(); }), "bounds/max_m");
}

TEST(ClassTable, IdsAreOneBasedAndResolutionFallsBack) {
  ClassTable ct;
  ct.names = {"chair", "table"};
  ct.resolution_m = {{"chair", 0.02}};
  ct.default_resolution_m = 0.05;
  EXPECT_EQ(ct.id("chair"), 1);
  EXPECT_EQ(ct.id("table"), 2);
  EXPECT_EQ(ct.id("sofa"), 0);
  EXPECT_EQ(ct.name(2), "table");
  EXPECT_EQ(ct.name(0), "");
  EXPECT_EQ(ct.name(3), "");
  EXPECT_TRUE(ct.isOfInterest(1));
  EXPECT_FALSE(ct.isOfInterest(2));
  EXPECT_DOUBLE_EQ(ct.resolution(1), 0.02);
  EXPECT_DOUBLE_EQ(ct.resolution(2), 0.05);
}

TEST(Config, ObjectNoiseBandMustBeNonNegative) {
  ObjectMapConfig c;
  c.behind_surface_quadratic_per_m = -0.001;
  EXPECT_EQ(rejected([&] { c.validate(); }), "object_map/behind_surface_quadratic_per_m");
  c.behind_surface_quadratic_per_m = 0.0;  // a fixed band
  EXPECT_EQ(rejected([&] { c.validate(); }), "");
}
