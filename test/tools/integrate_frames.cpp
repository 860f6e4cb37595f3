// Integrates depth frames straight through the core background map, as
// background_map_node does (metres from 16UC1 millimetres, the unknown space
// near the first pose marked free), and writes its occupied voxel centres:
// the reference a replayed bag's map is compared with
// (test/python/test_replay_realsense.py).
//
//   integrate_frames DIR OUT.ply [start_free_radius_m]
// DIR/camera.txt: "width height fx fy cx cy" (px); DIR/frames.txt: one line
// per frame "file tx ty tz qx qy qz qw" (T_WC, m), `file` a raw little-endian
// 16-bit depth image in mm (DIR-relative). Map settings and bounds are the
// core defaults (= config/semantic.yaml).
#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "semantic_exploration/core/occupancy_map.hpp"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: integrate_frames DIR OUT.ply [start_free_radius_m]\n";
    return 2;
  }
  const std::string dir = argv[1];
  const double free_radius_m = argc > 3 ? std::stod(argv[3]) : 0.5;
  semexp::PinholeCamera cam;
  std::ifstream cf(dir + "/camera.txt");
  if (!(cf >> cam.width >> cam.height >> cam.fx >> cam.fy >> cam.cx >> cam.cy)) {
    std::cerr << "cannot read " << dir << "/camera.txt\n";
    return 1;
  }
  semexp::OccupancyMap map{semexp::BackgroundMapConfig(), semexp::Bounds()};
  std::ifstream ff(dir + "/frames.txt");
  std::string line;
  int n = 0;
  while (std::getline(ff, line)) {
    std::istringstream ls(line);
    std::string file;
    double t[3], q[4];
    if (!(ls >> file >> t[0] >> t[1] >> t[2] >> q[0] >> q[1] >> q[2] >> q[3])) continue;
    std::vector<std::uint16_t> mm(static_cast<std::size_t>(cam.width) * cam.height);
    std::ifstream df(dir + "/" + file, std::ios::binary);
    if (!df.read(reinterpret_cast<char*>(mm.data()), static_cast<std::streamsize>(mm.size() * 2))) {
      std::cerr << "cannot read " << file << "\n";
      return 1;
    }
    cv::Mat depth_m;
    cv::Mat(cam.height, cam.width, CV_16UC1, mm.data()).convertTo(depth_m, CV_32FC1, 1e-3);
    Eigen::Isometry3d T_WC = Eigen::Isometry3d::Identity();
    T_WC.linear() = Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized().toRotationMatrix();
    T_WC.translation() = Eigen::Vector3d(t[0], t[1], t[2]);
    map.integrate(depth_m, cv::Mat(), cam, T_WC);
    if (n++ == 0 && free_radius_m > 0) map.markFreeSphere(T_WC.translation(), free_radius_m);
    map.updateFrontiers();
  }
  map.exportOccupiedPly(argv[2]);
  std::printf("integrated %d frames into %s\n", n, argv[2]);
  return n > 0 ? 0 : 1;
}
