// Background map integration speed against OctoMap, measured in one run (ours
// over all frames, then OctoMap over the same frames) on
// the same frames at the same resolution (4 cm) and range (10 m):
//   ours:    OccupancyMap::integrate with colour and minimum distance on
//   OctoMap: depth -> world point cloud, insertPointCloud(discretize = true)
//            + updateInnerOccupancy (what the box-room README's reference
//            figures measured)
// Sequences: box-room-tum (40 recorded 320x240 frames; README reference
// figures: OctoMap ~85 ms, supereight2 MultiresOFusion ~9 ms without colour,
// ~12 ms with colour) and a house-sized sequence rendered analytically here.
// Also: memory of both maps, frontier update time per frame (and whether it
// stays flat as the map grows) and one batch of 20 gain raycasts of 36 x 10.
//
// Integration runs on one thread and on two (integration_threads), same map.
//
// Usage: bench_background_map [--data DIR] [--frames N] [--ours-only] [--save-map PREFIX] [--out FILE]
//   --frames: house frames (0 skips the house); --ours-only skips OctoMap (profiling).
//   --save-map: writes PREFIX.<sequence>.t1.map / .t2.map (the saved maps after
//   the one- and two-thread runs, equal to the byte) and PREFIX.<sequence>.t1.updates
//   (every frame's update message), outside the timed code, so that two builds
//   can be compared byte for byte (cmp).
//   DIR defaults to ../shared/data/box-room-tum relative to the repository.
#include <octomap/OcTree.h>

#include <cstdio>
#include <ctime>
#include <cstring>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "semexp_test/box_room.hpp"
#include "bench_common.hpp"
#include "semantic_exploration/core/occupancy_map.hpp"

using semexp_bench::Clock;
using semexp_bench::median;
using semexp_bench::msSince;

namespace {

struct Frame {
  std::vector<float> depth_m;
  std::vector<std::uint8_t> rgb;
  Eigen::Isometry3d T_WC;
};

std::string defaultDataDir() {
  // <repo>/../shared/data/box-room-tum, set by CMake as an absolute path
  return SEMEXP_DEFAULT_BOX_ROOM_DIR;
}

std::vector<std::pair<double, std::string>> readList(const std::string& path) {
  std::vector<std::pair<double, std::string>> out;
  std::ifstream f(path);
  std::string line;
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ss(line);
    double t;
    std::string rest;
    ss >> t;
    std::getline(ss, rest);
    rest.erase(0, rest.find_first_not_of(' '));
    out.emplace_back(t, rest);
  }
  return out;
}

std::vector<Frame> loadTum(const std::string& dir, const semexp::PinholeCamera& cam) {
  std::vector<Frame> frames;
  const auto depth = readList(dir + "/depth.txt"), rgb = readList(dir + "/rgb.txt"), gt = readList(dir + "/groundtruth.txt");
  auto nearest = [](const std::vector<std::pair<double, std::string>>& l, double t) {
    std::size_t best = 0;
    for (std::size_t i = 1; i < l.size(); ++i)
      if (std::abs(l[i].first - t) < std::abs(l[best].first - t)) best = i;
    return best;
  };
  for (const auto& d : depth) {
    const cv::Mat d16 = cv::imread(dir + "/" + d.second, cv::IMREAD_UNCHANGED);
    if (d16.empty() || d16.type() != CV_16UC1 || d16.cols != cam.width || d16.rows != cam.height) {
      std::fprintf(stderr, "cannot read %s as 16-bit %dx%d\n", d.second.c_str(), cam.width, cam.height);
      continue;
    }
    Frame fr;
    cv::Mat dm;
    d16.convertTo(dm, CV_32FC1, 1.0 / 5000.0);
    fr.depth_m.assign(dm.ptr<float>(), dm.ptr<float>() + dm.total());
    if (!rgb.empty()) {
      cv::Mat bgr = cv::imread(dir + "/" + rgb[nearest(rgb, d.first)].second, cv::IMREAD_COLOR), c;
      if (!bgr.empty()) {
        cv::cvtColor(bgr, c, cv::COLOR_BGR2RGB);
        fr.rgb.assign(c.ptr<std::uint8_t>(), c.ptr<std::uint8_t>() + c.total() * 3);
      }
    }
    std::istringstream ss(gt[nearest(gt, d.first)].second);
    double tx, ty, tz, qx, qy, qz, qw;
    ss >> tx >> ty >> tz >> qx >> qy >> qz >> qw;
    fr.T_WC = Eigen::Isometry3d::Identity();
    fr.T_WC.linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
    fr.T_WC.translation() = Eigen::Vector3d(tx, ty, tz);
    frames.push_back(std::move(fr));
  }
  return frames;
}

// A single-storey house of 16 x 12 x 2.8 m: six rooms separated by 12 cm
// walls with doorways, furniture boxes; the camera walks through all rooms.
std::vector<Frame> houseSequence(const semexp::PinholeCamera& cam, int n) {
  semexp_test::BoxRoom s;
  s.room = {{0.013, 0.013, 0.013}, {16.013, 12.013, 2.813}};
  auto wall = [&](double x0, double y0, double x1, double y1) {
    s.boxes.push_back({{x0, y0, 0.0}, {x1, y1, 2.813}});
  };
  // interior walls along x = 5.3 and x = 10.7 and y = 6.0, with 1 m doorways
  for (double x : {5.3, 10.7}) {
    wall(x, 0.0, x + 0.12, 2.5);
    wall(x, 3.5, x + 0.12, 8.5);
    wall(x, 9.5, x + 0.12, 12.013);
  }
  wall(0.0, 6.0, 2.0, 6.12);
  wall(3.0, 6.0, 7.5, 6.12);
  wall(8.5, 6.0, 13.0, 6.12);
  wall(14.0, 6.0, 16.013, 6.12);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> ux(0.5, 15.5), uy(0.5, 11.5), us(0.4, 1.2), uh(0.4, 1.8);
  for (int i = 0; i < 24; ++i) {
    const double x = ux(rng), y = uy(rng), sx = us(rng), sy = us(rng), h = uh(rng);
    s.boxes.push_back({{x, y, 0.013}, {x + sx, y + sy, 0.013 + h}});
  }
  // waypoints through the doorways; the camera yaws continuously
  const std::vector<Eigen::Vector3d> wp = {{2.5, 3.0, 1.4},  {4.5, 3.0, 1.4},  {7.5, 3.0, 1.4},  {9.5, 3.0, 1.4},
                                           {13.0, 3.0, 1.4}, {13.5, 6.0, 1.4}, {13.0, 9.0, 1.4}, {8.0, 9.0, 1.4},
                                           {3.0, 9.0, 1.4},  {2.5, 6.0, 1.4},  {2.5, 3.0, 1.4}};
  std::vector<Frame> frames;
  for (int i = 0; i < n; ++i) {
    const double u = static_cast<double>(i) / n * (wp.size() - 1);
    const std::size_t k = static_cast<std::size_t>(u);
    const double a = u - k;
    const Eigen::Vector3d p = (1 - a) * wp[k] + a * wp[std::min(k + 1, wp.size() - 1)];
    Frame f;
    f.T_WC = semexp_test::lookPose(p, 0.35 * i, 0.15);
    f.depth_m = s.render(cam, f.T_WC);
    f.rgb.assign(static_cast<std::size_t>(cam.width) * cam.height * 3, 0);
    for (std::size_t j = 0; j < f.rgb.size(); ++j) f.rgb[j] = static_cast<std::uint8_t>((j * 7) & 0xFF);
    frames.push_back(std::move(f));
  }
  return frames;
}

// CPU time of this thread, ms: what one core spent, unaffected by other
// processes competing for the machine (wall time is reported as well).
double threadCpuMs() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}
// CPU time of all threads of the process, ms (the two-thread integration's total work).
double processCpuMs() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

bool g_ours_only = false;  // --ours-only: skip OctoMap (for profiling our side)
std::string g_save_prefix;  // --save-map PREFIX: save the maps and update messages (empty: off)

// Appends one update message's fields to `f` as raw bytes.
void appendUpdate(std::ofstream& f, const semexp::MapBlocksData& u) {
  auto put = [&f](const void* p, std::size_t n) { f.write(static_cast<const char*>(p), static_cast<std::streamsize>(n)); };
  put(&u.sequence, sizeof(u.sequence));
  const std::uint64_t n[4] = {u.coords.size(), u.payload.size(), u.uniform_coords.size(), u.uniform_values.size()};
  put(n, sizeof(n));
  put(u.coords.data(), u.coords.size() * sizeof(std::int32_t));
  put(u.payload.data(), u.payload.size());
  put(u.uniform_coords.data(), u.uniform_coords.size() * sizeof(std::int32_t));
  put(u.uniform_values.data(), u.uniform_values.size());
}

/// Returns false if a result is wrong (the tracked surface count differs from the full count).
bool run(const std::string& name, const std::vector<Frame>& frames, const semexp::PinholeCamera& cam,
         const semexp::Bounds& bounds, semexp_bench::Reporter& rep) {
  semexp::BackgroundMapConfig cfg;  // 4 cm, colour and minimum distance on
  cfg.free_margin_quadratic_per_m = 0.0;  // OctoMap carves free space up to the measured depth: compare like with like
  cfg.integration_threads = 1;
  semexp::OccupancyMap map(cfg, bounds);
  octomap::OcTree tree(cfg.resolution_m);
  std::vector<double> ours, fr, oct, ours_cpu, fr_cpu, oct_cpu, ours2, ours2_cpu;
  // The same frames on two threads first (wall time: the second thread's CPU
  // is not this thread's), then on one; the maps are identical.
  {
    semexp::BackgroundMapConfig cfg2 = cfg;
    cfg2.integration_threads = 2;
    semexp::OccupancyMap map2(cfg2, bounds);
    for (const Frame& f : frames) {
      const auto t0 = Clock::now();
      const double c0 = processCpuMs();
      map2.integrate(f.depth_m.data(), f.rgb.empty() ? nullptr : f.rgb.data(), cam, f.T_WC);
      ours2.push_back(msSince(t0));
      ours2_cpu.push_back(processCpuMs() - c0);
      map2.updateFrontiers();
      if (!g_save_prefix.empty()) map2.takeUpdate();  // as the one-thread run, so the saved maps compare equal
    }
    if (!g_save_prefix.empty()) map2.save(g_save_prefix + "." + name + ".t2.map");
  }
  std::ofstream updates;
  if (!g_save_prefix.empty()) updates.open(g_save_prefix + "." + name + ".t1.updates", std::ios::binary);
  for (const Frame& f : frames) {
    auto t0 = Clock::now();
    double c0 = threadCpuMs();
    map.integrate(f.depth_m.data(), f.rgb.empty() ? nullptr : f.rgb.data(), cam, f.T_WC);
    ours.push_back(msSince(t0));
    ours_cpu.push_back(threadCpuMs() - c0);
    t0 = Clock::now();
    c0 = threadCpuMs();
    map.updateFrontiers();
    fr.push_back(msSince(t0));
    fr_cpu.push_back(threadCpuMs() - c0);
    if (updates.is_open()) appendUpdate(updates, map.takeUpdate());
  }
  if (!g_save_prefix.empty()) map.save(g_save_prefix + "." + name + ".t1.map");
  // OctoMap on the same frames, after ours (interleaving the two would let
  // each evict the other's working set from the caches).
  for (const Frame& f : frames) {
    if (g_ours_only) break;
    const auto t0 = Clock::now();
    const double c0 = threadCpuMs();
    octomap::Pointcloud cloud;
    cloud.reserve(f.depth_m.size());
    for (int v = 0; v < cam.height; ++v)
      for (int u = 0; u < cam.width; ++u) {
        const float d = f.depth_m[static_cast<std::size_t>(v) * cam.width + u];
        if (!(d >= cam.d_min_m && d <= cam.d_max_m)) continue;
        const Eigen::Vector3d p = f.T_WC * (cam.ray_C(u, v).cast<double>() * d);
        cloud.push_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
      }
    const Eigen::Vector3d o = f.T_WC.translation();
    tree.insertPointCloud(cloud, octomap::point3d(o.x(), o.y(), o.z()), cam.d_max_m, false, true);
    tree.updateInnerOccupancy();
    oct.push_back(msSince(t0));
    oct_cpu.push_back(threadCpuMs() - c0);
  }
  const double mo = median(ours), mt = median(oct);
  const std::size_t third = std::max<std::size_t>(1, fr.size() / 3);
  // thread CPU time: what the update costs, whatever else runs on the machine
  const double fr_first = median(std::vector<double>(fr_cpu.begin(), fr_cpu.begin() + third));
  const double fr_last = median(std::vector<double>(fr_cpu.end() - third, fr_cpu.end()));
  double oct_explored = 0.0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) oct_explored += std::pow(it.getSize(), 3);

  // 20 gain raycasts of 36 x 10 from free positions along the camera path.
  std::vector<Eigen::Vector3d> pos;
  for (std::size_t i = 0; pos.size() < 20 && i < 4 * frames.size(); ++i) {
    const Eigen::Vector3d p = frames[(i * 7) % frames.size()].T_WC.translation() + Eigen::Vector3d(0.1 * (i % 5), 0.1 * (i % 3), 0.0);
    pos.push_back(p);
  }
  semexp::SphericalGrid grid;
  semexp::GainSettings gs;
  std::vector<double> gain_ms, gain_cpu;
  for (int r = 0; r < 5; ++r) {
    const auto t0 = Clock::now();
    const double c0 = threadCpuMs();
    const auto g = map.computeGains(pos, grid, gs);
    gain_ms.push_back(msSince(t0));
    gain_cpu.push_back(threadCpuMs() - c0);
    if (g.size() != pos.size()) return false;
  }

  // The termination's background share (surface seen from <= d_bg = 3 m) after every frame, with the deployed
  // settings (free margin on): counted again only where the frame changed it, against a full count of the
  // map every 5th frame. Both are this thread's CPU; the counts must agree. The tracked figure leaves out the
  // marking of changed cells, which integrate() does (it is in the integration figures).
  std::vector<double> tracked_cpu, full_cpu;
  bool counts_agree = true;
  {
    semexp::BackgroundMapConfig cfg_margin;  // defaults: 4 cm, free margin q = 0.006
    cfg_margin.integration_threads = 1;
    semexp::OccupancyMap map_margin(cfg_margin, bounds);
    for (std::size_t k = 0; k < frames.size(); ++k) {
      const Frame& f = frames[k];
      map_margin.integrate(f.depth_m.data(), f.rgb.empty() ? nullptr : f.rgb.data(), cam, f.T_WC);
      double c0 = threadCpuMs();
      const auto tracked = map_margin.trackSurfaceObservedWithin(3.0);
      tracked_cpu.push_back(threadCpuMs() - c0);
      if (k % 5 != 4) continue;
      c0 = threadCpuMs();
      const auto full = map_margin.surfaceObservedWithin(3.0);
      full_cpu.push_back(threadCpuMs() - c0);
      counts_agree = counts_agree && full.occupied_voxels == tracked.occupied_voxels &&
                     full.within_voxels == tracked.within_voxels;
    }
  }

  std::printf("\n== %s: %zu frames of %dx%d, r = %.2f m, d_max = %.0f m ==\n", name.c_str(), frames.size(),
              cam.width, cam.height, cfg.resolution_m, cam.d_max_m);
  const double mo_cpu = median(ours_cpu), mt_cpu = median(oct_cpu);
  std::printf("  integrate (colour + min distance)  ours %8.2f ms/frame   OctoMap %8.2f ms/frame   speed-up %.1fx  (wall, median)\n",
              mo, mt, mt / mo);
  std::printf("                                     ours %8.2f ms/frame   OctoMap %8.2f ms/frame   speed-up %.1fx  (thread CPU, median)\n",
              mo_cpu, mt_cpu, mt_cpu / mo_cpu);
  const double mo2 = median(ours2);
  std::printf("  integrate on 2 threads             ours %8.2f ms/frame   OctoMap %8.2f ms/frame   speed-up %.1fx  (wall, median; %.2fx one thread)\n",
              mo2, mt, mt / mo2, mo / mo2);
  std::printf("                                     ours %8.2f ms/frame CPU of both threads (median)\n", median(ours2_cpu));
  std::printf("  memory                             ours %8.2f MB         OctoMap %8.2f MB\n", map.memoryBytes() / 1e6,
              tree.memoryUsage() / 1e6);
  std::printf("  explored volume                    ours %8.2f m^3        OctoMap %8.2f m^3\n", map.exploredVolume(),
              oct_explored);
  std::printf("  frontier update                    %.2f ms/frame wall, %.2f ms CPU (median; CPU first third %.2f, last third %.2f), %zu frontiers\n",
              median(fr), median(fr_cpu), fr_first, fr_last, map.frontierCount());
  std::printf("  gain raycasts, 20 x 36x10          %.2f ms wall, %.2f ms CPU per batch (median of 5)\n", median(gain_ms),
              median(gain_cpu));
  const double tracked_med = median(tracked_cpu), full_med = median(full_cpu);
  std::printf("  surface seen from <= 3 m, per frame  tracked %.2f ms CPU   full count %.2f ms CPU   %.1fx"
              "  (median; free margin on; counts %s)\n",
              tracked_med, full_med, full_med / tracked_med, counts_agree ? "agree" : "DISAGREE");
  if (!counts_agree) std::fprintf(stderr, "%s: the tracked surface count differs from the full count\n", name.c_str());
  rep.add("background_map." + name + ".surface_share_tracked_cpu_ms", tracked_med, "ms", "full_count", full_med);
  rep.add("background_map." + name + ".surface_share_tracked_speedup", full_med / tracked_med, "x");
  rep.add("background_map." + name + ".integrate_ms_per_frame", mo, "ms", "octomap", mt);
  rep.add("background_map." + name + ".speedup_vs_octomap", mt / mo, "x");
  rep.add("background_map." + name + ".speedup_vs_octomap.threads_1", mt / mo, "x");
  rep.add("background_map." + name + ".speedup_vs_octomap.threads_2", mt / mo2, "x");
  rep.add("background_map." + name + ".integrate_ms_per_frame.threads_2", mo2, "ms", "octomap", mt);
  rep.add("background_map." + name + ".two_thread_speedup", mo / mo2, "x");
  rep.add("background_map." + name + ".integrate_cpu_ms_per_frame.threads_2", median(ours2_cpu), "ms");
  rep.add("background_map." + name + ".integrate_cpu_ms_per_frame", mo_cpu, "ms", "octomap", mt_cpu);
  rep.add("background_map." + name + ".frontier_update_cpu_ms_per_frame", median(fr_cpu), "ms");
  rep.add("background_map." + name + ".gain_batch_20x36x10_cpu_ms", median(gain_cpu), "ms");
  rep.add("background_map." + name + ".memory_mb", map.memoryBytes() / 1e6, "MB", "octomap", tree.memoryUsage() / 1e6);
  rep.add("background_map." + name + ".explored_m3", map.exploredVolume(), "m^3", "octomap", oct_explored);
  rep.add("background_map." + name + ".frontier_update_ms_per_frame", median(fr), "ms");
  rep.add("background_map." + name + ".frontier_update_cpu_ms_first_third", fr_first, "ms");
  rep.add("background_map." + name + ".frontier_update_cpu_ms_last_third", fr_last, "ms");
  rep.add("background_map." + name + ".gain_batch_20x36x10_ms", median(gain_ms), "ms");
  return counts_agree;
}

}  // namespace

int main(int argc, char** argv) {
  semexp_bench::Reporter rep(argc, argv);
  std::string data = defaultDataDir();
  int house_frames = 150;
  for (int i = 1; i < argc; ++i) g_ours_only = g_ours_only || std::strcmp(argv[i], "--ours-only") == 0;
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::strcmp(argv[i], "--data") == 0) data = argv[i + 1];
    if (std::strcmp(argv[i], "--frames") == 0) house_frames = std::atoi(argv[i + 1]);
    if (std::strcmp(argv[i], "--save-map") == 0) g_save_prefix = argv[i + 1];
  }
  semexp::PinholeCamera cam;  // 320 x 240, f = 262.5, 10 m
  semexp::Bounds bounds;      // default 20 x 20 x 4 m
  semexp::PinholeCamera tum = cam;
  tum.cx = 160.0;  // box-room README
  tum.cy = 120.0;
  const std::vector<Frame> box = loadTum(data, tum);
  bool ok = true;
  if (box.empty()) {
    std::fprintf(stderr, "no frames read from %s (pass --data DIR)\n", data.c_str());
  } else {
    ok = run("box_room_tum", box, tum, bounds, rep);
  }
  semexp::Bounds house_bounds;
  house_bounds.min_m = {-0.5, -0.5, -0.5};
  house_bounds.max_m = {16.5, 12.5, 3.3};
  if (house_frames > 0) ok = run("house", houseSequence(cam, house_frames), cam, house_bounds, rep) && ok;
  return box.empty() || !ok ? 1 : 0;
}
