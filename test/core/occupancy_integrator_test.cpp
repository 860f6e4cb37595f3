// Integrator: one frame onto a wall with known answers, and the same map
// from 1, 2 and 3 threads; the worker pool's CPU clock.
#include <gtest/gtest.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <limits>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "semexp_test/box_room.hpp"
#include "semantic_exploration/core/occupancy/integrator.hpp"
#include "semantic_exploration/core/occupancy_map.hpp"

using semexp::BackgroundMapConfig;
using semexp::Bounds;
using semexp::PinholeCamera;
using semexp::occupancy::BlockStore;
using semexp::occupancy::Integrator;
using semexp::occupancy::kUnknown;

namespace {

PinholeCamera smallCamera() { return semexp_test::centredCamera(64, 48, 50.0); }

// Temporary directory, removed with its files when the test ends.
struct TempDir {
  std::string path;
  TempDir() {
    char tmpl[] = "/tmp/semexp_integrator_XXXXXX";
    const char* p = mkdtemp(tmpl);
    path = p ? p : "/tmp";
  }
  ~TempDir() {
    for (const char* f : {"/a.map", "/b.map"}) std::remove((path + f).c_str());
    rmdir(path.c_str());
  }
};

std::string bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

// 10 cm voxels in cells of 4 (0.4 m), one thread; bounds of 1.6 m on a side from z = 0.
BackgroundMapConfig wallConfig() {
  BackgroundMapConfig cfg;
  cfg.resolution_m = 0.1;
  cfg.block_size = 4;
  cfg.integration_threads = 1;
  return cfg;
}
Bounds wallBounds() {
  Bounds bounds;
  bounds.min_m = {-0.8, -0.8, 0.0};
  bounds.max_m = {0.8, 0.8, 1.6};
  return bounds;
}

}  // namespace

TEST(Integrator, AWallInFrontOfTheCamera) {
  const BackgroundMapConfig cfg = wallConfig();
  BlockStore store(cfg.resolution_m, cfg.block_size, wallBounds(), cfg.integrate_colour);
  Integrator integ(cfg);
  const PinholeCamera cam = smallCamera();
  // Camera at (0.05, 0.05, -0.3) looking along world +z (optical = world axes),
  // a wall at z-depth 1.35 m, i.e. world z = 1.05; three invalid pixels.
  Eigen::Isometry3d T_WC = Eigen::Isometry3d::Identity();
  T_WC.translation() = Eigen::Vector3d(0.05, 0.05, -0.3);
  std::vector<float> depth(static_cast<std::size_t>(cam.width) * cam.height, 1.35f);
  depth[0] = std::numeric_limits<float>::quiet_NaN();
  depth[1] = 0.f;
  depth[2] = 11.f;
  std::vector<int> changed;
  const auto st = integ.integrate(store, depth.data(), nullptr, cam, T_WC, changed);
  EXPECT_EQ(st.invalid_pixels, 3u);
  EXPECT_GT(st.changed_cells, 0u);
  EXPECT_EQ(st.changed_cells, changed.size());
  // The optical axis runs through the centres of voxels x = y = 8 (0.05 m).
  EXPECT_EQ(store.voxelValue(8, 8, 0), -400);   // z 0.05: free, log-odds -0.4
  EXPECT_EQ(store.voxelValue(8, 8, 9), -400);   // z 0.95: in front of the wall
  EXPECT_EQ(store.voxelValue(8, 8, 10), 850);   // z 1.05: holds the endpoints, +0.85
  EXPECT_EQ(store.voxelValue(8, 8, 11), kUnknown);  // z 1.15: behind the band (2 cm)
  // The wall's cell got a block and a surface slot with the distance 1.35 m.
  const int cell = store.cellIndex(2, 2, 2);
  ASSERT_GE(store.cell_block[cell], 0);
  const int sl = store.block_surf[store.cell_block[cell]];
  ASSERT_GE(sl, 0);
  EXPECT_EQ(store.dist(sl)[store.voxelIndex(0, 0, 2)], 1350);
  // every changed cell once
  std::vector<int> sorted = changed;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(std::unique(sorted.begin(), sorted.end()), sorted.end());
}

// SurfaceChanges name the cells where a voxel changed between unknown, free and occupied, and those where an
// occupied voxel's distance went down; log-odds that only grow within a state name neither. The wall of
// AWallInFrontOfTheCamera, seen four times.
TEST(Integrator, SurfaceChangesNameTheCellsWhoseStateOrDistanceChanged) {
  const BackgroundMapConfig cfg = wallConfig();
  BlockStore store(cfg.resolution_m, cfg.block_size, wallBounds(), cfg.integrate_colour);
  Integrator integ(cfg);
  // 127 deg wide: the cells of z 0.4-0.8 lie wholly inside the view, in front of the wall, and are freed whole.
  const PinholeCamera cam = semexp_test::centredCamera(64, 48, 16.0);
  const auto cellSet = [](std::vector<int> v) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    return v;
  };
  using semexp::occupancy::SurfaceChanges;
  const auto frame = [&](double cam_z, float depth_m, std::vector<int>& changed, SurfaceChanges& sc) {
    Eigen::Isometry3d T_WC = Eigen::Isometry3d::Identity();
    T_WC.translation() = Eigen::Vector3d(0.05, 0.05, cam_z);
    const std::vector<float> depth(static_cast<std::size_t>(cam.width) * cam.height, depth_m);
    changed.clear();
    sc.clear();
    integ.integrate(store, depth.data(), nullptr, cam, T_WC, changed, &sc);
  };
  const auto occupiedCells = [&] {  // cells holding an occupied voxel
    std::vector<int> out;
    for (int c = 0; c < static_cast<int>(store.cellCount()); ++c) {
      const Eigen::Vector3i v0 = store.cellCoords(c) * store.bs;
      bool any = false;
      for (int i = 0; i < store.bs3 && !any; ++i)
        any = store.voxelValue(v0.x() + (i & 3), v0.y() + ((i >> 2) & 3), v0.z() + (i >> 4)) >= 0;
      if (any) out.push_back(c);
    }
    return out;
  };
  const int wall_cell = store.cellIndex(2, 2, 2);  // world z 0.8-1.2, holding the wall at z = 1.05
  std::vector<int> changed;
  semexp::occupancy::SurfaceChanges sc;
  // 1. Everything was unknown: every changed cell changed state; the wall's voxels got a distance.
  frame(-0.3, 1.35f, changed, sc);
  ASSERT_GT(changed.size(), 10u);
  EXPECT_EQ(cellSet(sc.state_changed), cellSet(changed));
  ASSERT_EQ(occupiedCells().size(), 16u);  // the cells of z 0.8-1.2 across the whole bounds
  int uniform_free = 0;  // cells freed whole, as uniform leaves (the other path through the update)
  for (int c = 0; c < static_cast<int>(store.cellCount()); ++c)
    uniform_free += store.cell_block[c] < 0 && store.cell_value[c] != kUnknown;
  ASSERT_GT(uniform_free, 0);
  EXPECT_EQ(cellSet(sc.distance_changed), occupiedCells());
  // 2. The same view: log-odds grow (free -0.4 -> -0.8, occupied 0.85 -> 1.7), states and distances stay.
  frame(-0.3, 1.35f, changed, sc);
  EXPECT_GT(changed.size(), 10u);
  EXPECT_TRUE(sc.state_changed.empty());
  EXPECT_TRUE(sc.distance_changed.empty());
  // 3. The wall 0.2 m farther (z = 1.25): the wall's old cell lies wholly in front of it, is freed as a whole
  // (its unknown voxels behind the old wall become free) and changes state; the old wall stays occupied
  // (1.7 - 0.4 = 1.3).
  frame(-0.3, 1.55f, changed, sc);
  const std::vector<int> state3 = cellSet(sc.state_changed);
  EXPECT_TRUE(std::binary_search(state3.begin(), state3.end(), wall_cell));
  EXPECT_EQ(store.voxelValue(8, 8, 11), -400);  // z 1.15: was unknown behind the old wall, now free
  EXPECT_EQ(store.voxelValue(8, 8, 10), 1300);  // z 1.05: the old wall, still occupied
  // 4. 0.2 m closer to the same wall: within the known free space, so no state changes; the distances of
  // both walls' voxels go down (the old one, still occupied at 1.3 - 0.4 = 0.9, is freed from closer).
  frame(-0.1, 1.35f, changed, sc);
  EXPECT_TRUE(sc.state_changed.empty());
  EXPECT_EQ(store.voxelValue(8, 8, 10), 900);
  const std::vector<int> dist4 = cellSet(sc.distance_changed);
  EXPECT_TRUE(std::binary_search(dist4.begin(), dist4.end(), store.cellIndex(2, 2, 3)));  // z 1.2-1.6
  EXPECT_TRUE(std::binary_search(dist4.begin(), dist4.end(), wall_cell));
  EXPECT_EQ(dist4, occupiedCells());
}

TEST(Integrator, ThreadCountDoesNotChangeTheMap) {
  const semexp_test::BoxRoom room = semexp_test::standardRoom();
  const PinholeCamera cam = smallCamera();
  Bounds bounds;
  bounds.min_m = {-3.2, -2.2, -0.2};
  bounds.max_m = {3.2, 2.7, 2.9};
  std::vector<std::vector<float>> frames;
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < 12; ++i) {
    poses.push_back(semexp_test::lookPose(Eigen::Vector3d(-1.0 + 0.15 * i, 0.2, 1.3), 0.55 * i, 0.2));
    frames.push_back(room.render(cam, poses.back()));
  }
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(cam.width) * cam.height * 3);
  for (std::size_t j = 0; j < rgb.size(); ++j) rgb[j] = static_cast<std::uint8_t>((j * 13) & 0xFF);
  TempDir dir;
  std::string saved[4];
  std::vector<semexp::MapBlocksData> updates[4];
  std::size_t frontiers[4];
  for (int threads = 1; threads <= 3; ++threads) {
    BackgroundMapConfig cfg;
    cfg.integration_threads = threads;
    semexp::OccupancyMap map(cfg, bounds);
    for (std::size_t i = 0; i < frames.size(); ++i) {
      map.integrate(frames[i].data(), rgb.data(), cam, poses[i]);
      map.updateFrontiers();
      updates[threads].push_back(map.takeUpdate());
    }
    const std::string path = dir.path + (threads == 1 ? "/a.map" : "/b.map");
    map.save(path);
    saved[threads] = bytes(path);
    frontiers[threads] = map.frontierCount();
  }
  ASSERT_GT(saved[1].size(), 1000u);
  for (int threads = 2; threads <= 3; ++threads) {
    // The own format holds every voxel's log-odds, distance, colour and frontier bits.
    EXPECT_TRUE(saved[threads] == saved[1]) << threads << " threads";
    EXPECT_EQ(frontiers[threads], frontiers[1]);
    ASSERT_EQ(updates[threads].size(), updates[1].size());
    for (std::size_t i = 0; i < updates[1].size(); ++i) {
      EXPECT_EQ(updates[threads][i].coords, updates[1][i].coords) << "frame " << i;
      EXPECT_EQ(updates[threads][i].payload, updates[1][i].payload) << "frame " << i;
    }
  }
}

TEST(Integrator, UsesTheConfiguredThreads) {
  BackgroundMapConfig cfg;
  cfg.integration_threads = 3;
  EXPECT_EQ(Integrator(cfg).threads(), 3);
  cfg.integration_threads = 0;
  EXPECT_THROW(cfg.validate(), semexp::ConfigError);
}

namespace {

double threadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// Runs two tasks on a 2-thread pool, one per thread (each waits until both
// have started); the task on `busy_caller ? the caller : the worker` spins
// until its thread has used 40 ms of CPU. Returns the pool's workerCpuSeconds() change.
double workerCpuOfTwoTasks(semexp::occupancy::WorkerPool& pool, bool busy_caller) {
  const double before = pool.workerCpuSeconds();
  const auto caller = std::this_thread::get_id();
  std::mutex m;
  std::condition_variable cv;
  int started = 0;
  pool.run(2, [&](std::size_t) {
    {
      std::unique_lock<std::mutex> lock(m);
      ++started;
      cv.notify_all();
      cv.wait(lock, [&] { return started == 2; });
    }
    if ((std::this_thread::get_id() == caller) != busy_caller) return;
    const double t0 = threadCpuSeconds();
    volatile double x = 0;
    while (threadCpuSeconds() - t0 < 0.040) x = x + 1.0;
  });
  return pool.workerCpuSeconds() - before;
}

}  // namespace

// The caller's thread CPU clock misses what the pool's worker does for it:
// workerCpuSeconds() is that part, and only that part.
TEST(WorkerPool, WorkerCpuSecondsCountsThePoolThreadsOnly) {
  semexp::occupancy::WorkerPool single(1);
  EXPECT_EQ(single.workerCpuSeconds(), 0.0);
  semexp::occupancy::WorkerPool pool(2);
  EXPECT_GE(workerCpuOfTwoTasks(pool, false), 0.040);  // the worker spun 40 ms
  EXPECT_LT(workerCpuOfTwoTasks(pool, true), 0.020);   // the caller spun; the worker only waited
}

TEST(Integrator, BlendColourIsTheRoundedRunningMean) {
  // Hand-computed: weight 0 takes the new value; (200 * 3 + 100 + 2) / 4 = 175;
  // (255 * 255 + 0 + 128) / 256 = 254; (10 * 1 + 11 + 1) / 2 = 11.
  EXPECT_EQ(semexp::occupancy::blendColour(37, 0, 90), 90);
  EXPECT_EQ(semexp::occupancy::blendColour(200, 3, 100), 175);
  EXPECT_EQ(semexp::occupancy::blendColour(255, 255, 0), 254);
  EXPECT_EQ(semexp::occupancy::blendColour(10, 1, 11), 11);
  // The table reciprocal equals the integer division everywhere.
  int wrong = 0;
  for (int w = 0; w < 256; ++w)
    for (int c = 0; c < 256; ++c)
      for (int in = 0; in < 256; ++in)
        wrong += semexp::occupancy::blendColour(c, w, in) != (c * w + in + (w + 1) / 2) / (w + 1);
  EXPECT_EQ(wrong, 0);
}
