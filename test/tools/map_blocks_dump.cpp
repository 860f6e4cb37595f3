// Writes MapBlocks messages as background_map sends them (core snapshot ->
// semexp_ros::toMapBlocksMsg -> roscpp serialisation) for a box room seen
// from two poses, and the C++ map's own answer at probe points: what
// test/python/test_map_blocks_codec.py decodes with the Python codec.
//
//   map_blocks_dump OUT_DIR
// OUT_DIR/full.bin, OUT_DIR/compact.bin: the serialised messages of a full and a
// compact (uniform blocks as one value) snapshot. OUT_DIR/probes.txt: one line
// per probe "x y z code" (a voxel centre, m, world; code = the int8 the voxel's log-odds
// encodes to, -128 = unknown or outside the map).
#include <Eigen/Geometry>
#include <ros/serialization.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include "semexp_test/box_room.hpp"
#include "semantic_exploration/core/occupancy_map.hpp"
#include "semantic_exploration/ros/conversions.hpp"

namespace {

bool writeMsg(const semantic_exploration::MapBlocks& m, const std::string& path) {
  const std::uint32_t n = ros::serialization::serializationLength(m);
  std::vector<std::uint8_t> buf(n);
  ros::serialization::OStream s(buf.data(), n);
  ros::serialization::serialize(s, m);
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(buf.data()), static_cast<std::streamsize>(buf.size()));
  return static_cast<bool>(f.flush());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: map_blocks_dump OUT_DIR\n";
    return 2;
  }
  const std::string dir = argv[1];
  const semexp_test::BoxRoom room = semexp_test::standardRoom();
  const semexp::Bounds bounds = room.bounds();
  semexp::BackgroundMapConfig cfg;  // 4 cm, 8^3 blocks
  semexp::OccupancyMap map(cfg, bounds);
  const semexp::PinholeCamera cam = semexp_test::halfSizeCamera();
  // Two views that see different walls, so that the map differs along every axis.
  for (const auto& T : {semexp_test::lookPose({-0.5, 0.0, 1.3}, 0.3, 0.2), semexp_test::lookPose({0.5, -0.5, 1.0}, 2.2, 0.4)}) {
    const std::vector<float> depth = room.render(cam, T);
    map.integrate(depth.data(), nullptr, cam, T);
  }
  map.markFreeSphere({0.0, 0.0, 1.3}, 0.5);  // uniform free blocks for the compact snapshot
  const ros::Time stamp(12.5);
  if (!writeMsg(semexp_ros::toMapBlocksMsg(map.snapshot(false), stamp, "world"), dir + "/full.bin") ||
      !writeMsg(semexp_ros::toMapBlocksMsg(map.snapshot(true), stamp, "world"), dir + "/compact.bin")) {
    std::cerr << "cannot write to " << dir << "\n";
    return 1;
  }
  std::ofstream probes(dir + "/probes.txt");
  // Voxel centres (a point on a voxel face could fall either way), some outside the map (unknown).
  std::mt19937 rng(7);
  const double res = map.resolution();
  const Eigen::Vector3i n = ((map.extentMax() - map.extentMin()) / res).array().round().cast<int>();
  std::uniform_int_distribution<int> ix(-5, n.x() + 4), iy(-5, n.y() + 4), iz(-5, n.z() + 4);
  char line[160];
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector3d p = map.extentMin() + (Eigen::Vector3d(ix(rng), iy(rng), iz(rng)).array() + 0.5).matrix() * res;
    double l = 0.0;
    const int code = map.logOdds(p, l)
                         ? semexp::map_blocks::encodeMilli(static_cast<std::int16_t>(std::lround(l * 1000.0)))
                         : semexp::map_blocks::kUnknownI8;
    std::snprintf(line, sizeof line, "%.17g %.17g %.17g %d\n", p.x(), p.y(), p.z(), code);
    probes << line;
  }
  return probes.flush() ? 0 : 1;
}
