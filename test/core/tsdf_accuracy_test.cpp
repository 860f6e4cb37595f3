// Accuracy of the object TSDF in the spirit of voxblox's integrator test:
// noise-free depth of analytic shapes from a ring of poses, compared with the
// exact signed distance, at 1, 2 and 4 cm.

#include <gtest/gtest.h>

#include <cstdio>

#include "semantic_exploration/core/tsdf.hpp"
#include "semexp_test/cameras.hpp"
#include "semexp_test/rendering.hpp"

using semexp::PinholeCamera;
using semexp::TsdfMap;
using semexp::TsdfParams;
using namespace semexp_test;

namespace {

struct Errors {
  double rmse_m = 0, max_m = 0;
  size_t n = 0;
  double mesh_max_m = 0;
  size_t mesh_vertices = 0;
};

template <class Map>
Errors integrateAndMeasure(Map& map, const Shape& shape, const PinholeCamera& cam) {
  std::vector<Eigen::Isometry3d> poses = ring(Eigen::Vector3d::Zero(), 1.0, 0.5, 10);
  for (const auto& T : ring(Eigen::Vector3d::Zero(), 1.0, -0.5, 10, 0.3)) poses.push_back(T);
  for (const auto& T_WC : poses) {
    cv::Mat depth, labels;
    renderShapes(cam, T_WC, {&shape}, depth, labels);
    const cv::Mat mask = labels > 0;
    map.integrate(cam, T_WC, depth, cv::Mat(), mask, true);
  }
  // RMSE over the voxels next to the surface (|true SDF| <= one voxel: they
  // place the zero crossing); maximum error over the band the TSDF updates
  // behind and in front of the surface.
  const double trunc = map.params().truncation_m, res = map.params().resolution_m;
  Errors e;
  double sq = 0;
  size_t n_band = 0;
  map.forEachVoxel([&](const Eigen::Vector3i& idx, const typename Map::Voxel& vx) {
    if (vx.weight() <= 0) return;
    const double truth = shape.sdf(map.voxelCentre(idx).template cast<double>());
    if (truth < -map.params().behind_surface_m || truth > trunc) return;
    const double err = std::abs(vx.sdf(static_cast<float>(trunc)) - truth);
    e.max_m = std::max(e.max_m, err);
    ++n_band;
    if (std::abs(truth) > res) return;
    sq += err * err;
    ++e.n;
  });
  e.rmse_m = e.n ? std::sqrt(sq / e.n) : 0;
  const semexp::Mesh mesh = map.extractMesh();
  e.mesh_vertices = mesh.vertices_W.size();
  for (const auto& v : mesh.vertices_W) e.mesh_max_m = std::max(e.mesh_max_m, std::abs(shape.sdf(v.cast<double>())));
  std::printf("res %.3f m: %zu voxels next to the surface, TSDF RMSE %.4f m; max error %.4f m over %zu voxels of the band (trunc %.3f); "
              "%zu mesh vertices, max distance to surface %.4f m\n",
              res, e.n, e.rmse_m, e.max_m, n_band, trunc, e.mesh_vertices, e.mesh_max_m);
  return e;
}

class TsdfAccuracy : public ::testing::TestWithParam<double> {};

void checkShape(const Shape& shape, double res) {
  PinholeCamera cam;
  TsdfParams p;
  p.resolution_m = res;
  p.truncation_m = 4 * res;
  p.behind_surface_m = 2 * res;
  TsdfMap map(p);
  const Errors e = integrateAndMeasure(map, shape, cam);
  EXPECT_GT(e.n, 100u);
  EXPECT_LT(e.rmse_m, res);
  EXPECT_LT(e.max_m, p.truncation_m);
  EXPECT_GT(e.mesh_vertices, 100u);
  EXPECT_LT(e.mesh_max_m, res);
}

TEST_P(TsdfAccuracy, Sphere) { checkShape(Sphere(Eigen::Vector3d(0.01, -0.02, 0.005), 0.3), GetParam()); }

TEST_P(TsdfAccuracy, Box) {
  checkShape(Box::around(Eigen::Vector3d(0.013, 0.004, -0.007), Eigen::Vector3d(0.25, 0.2, 0.15)), GetParam());
}

INSTANTIATE_TEST_SUITE_P(Resolutions, TsdfAccuracy, ::testing::Values(0.01, 0.02, 0.04));

}  // namespace
