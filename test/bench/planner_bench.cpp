// Planning iteration time: n = 20 candidates, 36 x 10 raycasts, the default
// OMPL budget (0.1 s per candidate), all hardware threads, on a synthetic
// partially explored three-room map (dense voxel grid at 0.04 m). Prints the
// median iteration time and its parts (sampling, path planning, gains, yaw).
//
// The gain stage here runs a simple entropy raycast on the synthetic grid
// (the background/object map raycasts have their own benchmarks), so it
// measures the planner's own overhead plus a representative raycast.
// Peer: the paper reports 2.8 s per iteration on a Jetson Xavier NX; that is
// a reference value from the paper, not measured here.
#include <cstdio>
#include <thread>

#include <ompl/util/RandomNumbers.h>

#include "../core/planning_test_map.hpp"
#include "bench_common.hpp"
#include "semantic_exploration/core/planning/exploration_planner.hpp"

using semexp_test::TestGrid;

int main(int argc, char** argv) {
  semexp_bench::Reporter rep(argc, argv);
  ompl::RNG::setSeed(3);

  semexp::Bounds bounds;
  bounds.min_m = {0.0, 0.0, 0.0};
  bounds.max_m = {12.0, 8.0, 3.0};
  const double res = 0.04;
  // Three rooms along x separated by walls with doorways; the first two are
  // known free, the third unknown; floor and ceiling occupied.
  TestGrid grid(bounds, res, TestGrid::kUnknown);
  grid.fill_box({0.0, 0.0, 0.0}, {8.0, 8.0, 3.0}, TestGrid::kFree);
  grid.fill_box({0.0, 0.0, 0.0}, {12.0, 8.0, 0.1}, TestGrid::kOccupied);
  grid.fill_box({0.0, 0.0, 2.9}, {8.0, 8.0, 3.0}, TestGrid::kOccupied);
  grid.fill_box({3.9, 0.0, 0.0}, {4.1, 5.0, 3.0}, TestGrid::kOccupied);
  grid.fill_box({3.9, 6.0, 0.0}, {4.1, 8.0, 3.0}, TestGrid::kOccupied);
  grid.fill_box({7.9, 0.0, 0.0}, {8.1, 2.0, 3.0}, TestGrid::kOccupied);
  grid.fill_box({7.9, 3.0, 0.0}, {8.1, 8.0, 3.0}, TestGrid::kOccupied);
  grid.fill_box({7.9, 2.0, 0.0}, {8.1, 3.0, 3.0}, TestGrid::kFree);  // doorway into the unknown room
  // Four box objects (chairs) in the known rooms.
  std::vector<semexp::ObjectSummary> objects;
  const Eigen::Vector3d chairs[4] = {{1.5, 1.5, 0.5}, {2.5, 6.0, 0.5}, {5.5, 2.0, 0.5}, {6.5, 6.5, 0.5}};
  for (int i = 0; i < 4; ++i) {
    semexp::ObjectSummary o;
    o.id = static_cast<std::uint32_t>(i + 1);
    o.centroid_W = chairs[i];
    o.bbox_min_W = chairs[i] - Eigen::Vector3d(0.25, 0.25, 0.4);
    o.bbox_max_W = chairs[i] + Eigen::Vector3d(0.25, 0.25, 0.4);
    o.observed_fraction = 0.3;
    grid.fill_box(o.bbox_min_W, o.bbox_max_W, TestGrid::kOccupied);
    objects.push_back(o);
  }
  const std::vector<Eigen::Vector3d> frontiers = grid.frontiers();

  semexp::PlannerConfig config;  // defaults: n = 20, 36 x 10, 0.1 s per candidate
  semexp::ExplorationConfig exploration;
  semexp::PinholeCamera camera;
  semexp::SphericalGrid sgrid;
  sgrid.width = config.raycast_width;
  sgrid.height = config.raycast_height;
  sgrid.vfov_rad = camera.vfov_rad();

  semexp::ExplorationProviders prov;
  prov.is_free = [&grid](const Eigen::Vector3d& p, double r) { return grid.sphere_free(p, r); };
  prov.not_occupied = [&grid](const Eigen::Vector3d& p, double r) { return grid.sphere_not_occupied(p, r); };
  prov.gains = [&](const std::vector<Eigen::Vector3d>& ps) {
    std::vector<semexp::GainSet> out(ps.size());
    for (std::size_t i = 0; i < ps.size(); ++i) out[i].entropy = grid.entropy_gain(ps[i], sgrid, camera.d_min_m, camera.d_max_m);
    return out;
  };

  semexp::ExplorationPlanner planner(config, exploration, bounds, camera, res);
  const Eigen::Vector3d starts[5] = {{1.0, 4.0, 1.2}, {2.0, 2.0, 1.0}, {5.0, 4.0, 1.5}, {6.5, 1.0, 1.0}, {3.0, 7.0, 1.2}};
  std::vector<double> total, sampling, paths, gains, yaw;
  int reachable = 0, iterations = 0;
  const int kIterations = 15;
  for (int it = 0; it < kIterations; ++it) {
    semexp::ExplorationInputs in;
    in.position_W = starts[it % 5];
    in.yaw_rad = 0.5 * it;
    in.frontiers_W = frontiers;
    in.objects = objects;
    const semexp::IterationResult r = planner.plan(in, prov);
    if (r.winner < 0) std::fprintf(stderr, "iteration %d: no winner: %s\n", it, r.message.c_str());
    total.push_back(1e3 * r.total_s);
    sampling.push_back(1e3 * r.sampling_s);
    paths.push_back(1e3 * r.path_planning_s);
    gains.push_back(1e3 * r.gains_s);
    yaw.push_back(1e3 * r.yaw_s);
    reachable += r.candidates_reachable;
    iterations += 1;
  }

  std::printf("planner iteration on a synthetic 12 x 8 x 3 m map (0.04 m), n = %d, %d x %d raycasts, "
              "%.2f s OMPL budget per candidate, %u hardware threads, %zu frontiers, %d iterations\n",
              config.n_candidates, config.raycast_width, config.raycast_height, config.time_budget_s,
              std::thread::hardware_concurrency(), frontiers.size(), iterations);
  std::printf("  %-28s %10s\n", "stage", "median ms");
  std::printf("  %-28s %10.1f   (paper, Jetson Xavier NX: 2800 ms -- reference value, not measured here)\n",
              "total", semexp_bench::median(total));
  std::printf("  %-28s %10.2f\n", "sampling", semexp_bench::median(sampling));
  std::printf("  %-28s %10.1f\n", "path planning", semexp_bench::median(paths));
  std::printf("  %-28s %10.1f\n", "gains (synthetic raycast)", semexp_bench::median(gains));
  std::printf("  %-28s %10.1f\n", "intermediate yaw", semexp_bench::median(yaw));
  std::printf("  mean reachable candidates per iteration: %.1f of %d\n",
              static_cast<double>(reachable) / iterations, config.n_candidates);

  rep.add("planner_iteration_median", semexp_bench::median(total), "ms",
          "paper Jetson Xavier NX (reference value, not measured)", 2800.0);
  rep.add("planner_sampling_median", semexp_bench::median(sampling), "ms");
  rep.add("planner_path_planning_median", semexp_bench::median(paths), "ms");
  rep.add("planner_gains_median", semexp_bench::median(gains), "ms");
  rep.add("planner_yaw_median", semexp_bench::median(yaw), "ms");
  return 0;
}
