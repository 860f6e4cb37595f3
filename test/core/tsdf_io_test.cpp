// Saving and loading an object TSDF (tsdf_io.hpp): a loaded map holds every
// saved voxel bit for bit and gives the same mesh; damaged files are refused
// with a reason; the saved TSDFs of an object map remesh to its saved meshes.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <string>

#include "semantic_exploration/core/object_remesh.hpp"
#include "semantic_exploration/core/tsdf_io.hpp"
#include "semexp_test/cameras.hpp"
#include "semexp_test/object_scenes.hpp"
#include "semexp_test/rendering.hpp"
#include "semexp_test/temp_dir.hpp"

using namespace semexp;
using namespace semexp_test;
namespace fs = std::filesystem;

namespace {

using TsdfIoTest = TempDirTest;

constexpr int kChair = 1;  // "chair" in the default class table

// A sphere seen from 8 views round it, detected in every other one: voxels with every kind of content
// (negative SDF, foreground under and over 0.5, colour, a range of nearest distances).
void integrateSphere(TsdfMap& map) {
  const PinholeCamera cam;
  const Sphere sphere(Eigen::Vector3d(0.1, -0.05, 0.02), 0.25);
  int k = 0;
  for (const auto& T_WC : ring(sphere.centre, 1.0, 0.3, 8)) {
    cv::Mat depth, labels;
    renderShapes(cam, T_WC, {&sphere}, depth, labels);
    const cv::Mat rgb(depth.size(), CV_8UC3, cv::Scalar(10 * k, 200, 255 - 20 * k));
    map.integrate(cam, T_WC, depth, rgb, labels > 0, k++ % 2 == 0);
  }
}

std::string readAll(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

void writeAll(const fs::path& p, const std::string& s) { std::ofstream(p, std::ios::binary) << s; }

// A mesh as its set of triangles (vertex positions and colours, each triangle rotated to start at its
// least vertex, orientation kept), sorted: meshes that differ only in the order blocks were visited in
// (a hash map's order, which a loaded map need not share) compare equal.
using Corner = std::array<float, 6>;
std::vector<std::array<Corner, 3>> triangleSet(const Mesh& m) {
  std::vector<std::array<Corner, 3>> out;
  for (const auto& t : m.triangles) {
    std::array<Corner, 3> tri;
    for (int j = 0; j < 3; ++j) {
      const auto& p = m.vertices_W[t[j]];
      const auto& c = m.colours[t[j]];
      tri[j] = {p.x(), p.y(), p.z(), static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2])};
    }
    std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
    out.push_back(tri);
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST_F(TsdfIoTest, ALoadedMapHoldsEverySavedVoxel) {
  TsdfParams params = objectTsdfParams();
  params.full_weight_depth_m = 0.9;  // every saved parameter differs from its default
  params.behind_surface_quadratic_per_m = 0.006;
  params.foreground_prior = 0.3;
  params.foreground_prior_weight = 2.0;
  params.max_weight = 50.0;
  TsdfMap map(params);
  integrateSphere(map);
  ASSERT_GT(map.blockCount(), 20u);
  const fs::path path = dir_ / "sphere.tsdf";
  std::string error;
  ASSERT_TRUE(saveTsdf(map, path.string(), &error)) << error;
  const auto loaded = loadTsdf(path.string(), &error);
  ASSERT_TRUE(loaded) << error;
  const TsdfParams& q = loaded->params();
  EXPECT_EQ(q.resolution_m, params.resolution_m);
  EXPECT_EQ(q.truncation_m, params.truncation_m);
  EXPECT_EQ(q.behind_surface_m, params.behind_surface_m);
  EXPECT_EQ(q.behind_surface_quadratic_per_m, params.behind_surface_quadratic_per_m);
  EXPECT_EQ(q.full_weight_depth_m, params.full_weight_depth_m);
  EXPECT_EQ(q.foreground_prior, params.foreground_prior);
  EXPECT_EQ(q.foreground_prior_weight, params.foreground_prior_weight);
  EXPECT_EQ(q.block_size, params.block_size);
  EXPECT_EQ(q.max_weight, params.max_weight);
  EXPECT_EQ(loaded->blockCount(), map.blockCount());
  EXPECT_NE(loaded->revision(), map.revision());
  std::size_t compared = 0, negative_blocks = 0, fg_low = 0, fg_high = 0;
  map.forEachBlock([&](const Eigen::Vector3i& b, const std::vector<TsdfVoxel>& voxels, bool has_negative) {
    negative_blocks += has_negative;
    for (std::size_t i = 0; i < voxels.size(); ++i) {
      const Eigen::Vector3i v = b * params.block_size + Eigen::Vector3i(static_cast<int>(i % 8),
                                                                         static_cast<int>(i / 8 % 8),
                                                                         static_cast<int>(i / 64));
      const TsdfVoxel* w = loaded->voxel(v);
      ASSERT_NE(w, nullptr);
      const TsdfVoxel& u = voxels[i];
      ASSERT_EQ(u.sdf_q, w->sdf_q);
      ASSERT_EQ(u.weight_q, w->weight_q);
      ASSERT_EQ(u.min_distance_mm, w->min_distance_mm);
      ASSERT_EQ(u.foreground_q, w->foreground_q);
      ASSERT_EQ(u.rgb[0], w->rgb[0]);
      ASSERT_EQ(u.rgb[1], w->rgb[1]);
      ASSERT_EQ(u.rgb[2], w->rgb[2]);
      fg_low += u.weight_q > 0 && u.foreground() < 0.5f;
      fg_high += u.foreground() > 0.5f;
      ++compared;
    }
  });
  EXPECT_EQ(compared, map.voxelCount());
  EXPECT_GT(negative_blocks, 0u);
  EXPECT_GT(fg_low, 0u);
  EXPECT_GT(fg_high, 0u);
  std::size_t loaded_negative = 0;
  loaded->forEachBlock([&](const Eigen::Vector3i&, const std::vector<TsdfVoxel>&, bool n) { loaded_negative += n; });
  EXPECT_EQ(loaded_negative, negative_blocks);
  const Mesh a = map.extractMesh(), b = loaded->extractMesh();
  ASSERT_GT(a.triangles.size(), 500u);
  EXPECT_EQ(a.vertices_W.size(), b.vertices_W.size());
  EXPECT_TRUE(triangleSet(a) == triangleSet(b));
  // Saving the loaded map writes the same bytes (blocks in index order, whatever the hash map's).
  ASSERT_TRUE(saveTsdf(*loaded, (dir_ / "again.tsdf").string(), &error)) << error;
  EXPECT_EQ(readAll(dir_ / "again.tsdf"), readAll(path));
}

TEST_F(TsdfIoTest, DamagedFilesAreRefusedWithAReason) {
  TsdfMap map(objectTsdfParams());
  integrateSphere(map);
  const fs::path path = dir_ / "sphere.tsdf";
  ASSERT_TRUE(saveTsdf(map, path.string()));
  const std::string bytes = readAll(path);
  const auto reason = [&](const std::string& content) {
    writeAll(dir_ / "damaged.tsdf", content);
    std::string error;
    EXPECT_EQ(loadTsdf((dir_ / "damaged.tsdf").string(), &error), nullptr);
    return error;
  };
  std::string error;
  EXPECT_EQ(loadTsdf((dir_ / "missing.tsdf").string(), &error), nullptr);
  EXPECT_NE(error.find("cannot open"), std::string::npos) << error;
  EXPECT_NE(reason("ply\nformat ascii 1.0\n").find("not a semexp_tsdf file"), std::string::npos);
  EXPECT_NE(reason("semexp_tsdf 2" + bytes.substr(13)).find("format version 2"), std::string::npos);
  EXPECT_NE(reason(bytes.substr(0, bytes.size() - 1)).find("truncated at block"), std::string::npos);
  EXPECT_NE(reason(bytes + "x").find("bytes after the last block"), std::string::npos);
  std::string no_resolution = bytes;
  no_resolution.replace(no_resolution.find("resolution_m"), 12, "resolution_x");
  EXPECT_NE(reason(no_resolution).find("header unreadable"), std::string::npos);
}

TEST_F(TsdfIoTest, SavedTsdfsRemeshToTheSavedMeshes) {
  ObjectMapConfig c = objectMapConfigWithPrior();
  c.save_tsdf = true;
  c.mesh_max_sdf_std_m = 0.005;  // the gate the saved meshes were extracted under
  const PinholeCamera cam;
  const BoxUnion a = chair(0.0, -0.5), b = chair(0.0, 0.5);
  // Each chair seen all round (labels: 1 = a, 2 = b), as a detector would see them.
  const auto fly = [&](ObjectMap& m, int views) {
    for (const auto& T_WC : ring(Eigen::Vector3d(0.0, 0.0, 0.5), 1.8, 0.9, views)) {
      cv::Mat depth, labels;
      renderShapes(cam, T_WC, {&a, &b}, depth, labels);
      runFrame(m, cam, T_WC, depth, labels, {1, 2}, kChair);
    }
  };
  ObjectMap map(c, ClassTable());
  fly(map, 12);
  ASSERT_EQ(map.objects().size(), 2u);
  std::string error;
  const auto files = map.save((dir_ / "objects").string(), 1.0, &error);
  ASSERT_EQ(error, "");
  ASSERT_EQ(files.size(), 5u);  // 2 meshes, 2 TSDFs, the index
  std::vector<std::string> meshes;
  for (const std::string& f : files) {
    if (fs::path(f).extension() != ".ply") continue;
    meshes.push_back(fs::path(f).filename().string());
    const std::string tsdf = fs::path(f).stem().string() + ".tsdf";
    EXPECT_TRUE(fs::exists(dir_ / "objects" / tsdf)) << tsdf;
    EXPECT_NE(readAll(dir_ / "objects" / "objects.json").find("\"tsdf\": \"" + tsdf + "\""), std::string::npos);
  }
  ASSERT_EQ(meshes.size(), 2u);
  // The same gate gives the saved meshes (the same triangles) and the same index.
  ASSERT_EQ(remeshSavedObjects((dir_ / "objects").string(), (dir_ / "again").string(), c.meshGate(),
                               c.mesh_fragment_gap_m, &error), 2) << error;
  for (const std::string& name : meshes) {
    Mesh saved, again;
    ASSERT_TRUE(readPly((dir_ / "objects" / name).string(), saved));
    ASSERT_TRUE(readPly((dir_ / "again" / name).string(), again));
    ASSERT_GT(saved.triangles.size(), 200u) << name;
    EXPECT_TRUE(triangleSet(again) == triangleSet(saved)) << name;
  }
  EXPECT_EQ(readAll(dir_ / "again" / "objects.json"), readAll(dir_ / "objects" / "objects.json"));
  // A higher foreground bound keeps a part of each mesh.
  MeshGate strict = c.meshGate();
  strict.min_foreground = 0.7f;
  ASSERT_EQ(remeshSavedObjects((dir_ / "objects").string(), (dir_ / "strict").string(), strict,
                               c.mesh_fragment_gap_m, &error), 2) << error;
  for (const std::string& name : meshes) {
    Mesh saved, kept;
    ASSERT_TRUE(readPly((dir_ / "objects" / name).string(), saved));
    ASSERT_TRUE(readPly((dir_ / "strict" / name).string(), kept));
    EXPECT_GT(kept.triangles.size(), 0u) << name;
    EXPECT_LT(kept.triangles.size(), saved.triangles.size()) << name;
  }
  // A directory saved without TSDFs cannot be remeshed, and says why.
  c.save_tsdf = false;
  ObjectMap plain(c, ClassTable());
  fly(plain, 2);
  ASSERT_FALSE(plain.save((dir_ / "plain").string(), 1.0, &error).empty());
  EXPECT_EQ(remeshSavedObjects((dir_ / "plain").string(), (dir_ / "out").string(), c.meshGate(), 0.3, &error), -1);
  EXPECT_NE(error.find("save_tsdf true"), std::string::npos) << error;
}

}  // namespace
