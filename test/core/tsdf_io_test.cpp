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
  TsdfParams params = objectTsdfParams();  // every saved parameter differs from the TsdfParams defaults
  params.resolution_m = 0.03;
  params.truncation_m = 0.09;
  params.behind_surface_m = 0.05;
  params.block_size = 16;
  params.full_weight_depth_m = 0.9;
  params.behind_surface_quadratic_per_m = 0.006;
  params.foreground_prior = 0.3;
  params.foreground_prior_weight = 2.0;
  params.max_weight = 50.0;
  TsdfMap map(params);
  integrateSphere(map);
  ASSERT_GT(map.blockCount(), 4u);
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
  std::size_t compared = 0, negative_blocks = 0, fg_low = 0, fg_high = 0;
  map.forEachBlock([&](const Eigen::Vector3i& b, const std::vector<TsdfVoxel>& voxels, bool has_negative) {
    negative_blocks += has_negative;
    for (std::size_t i = 0; i < voxels.size(); ++i) {
      const int B = params.block_size, k = static_cast<int>(i);
      const Eigen::Vector3i v = b * B + Eigen::Vector3i(k % B, k / B % B, k / (B * B));
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
  std::string huge_blocks = bytes;  // 1024^3 voxels per block would be 10 GB: refused before allocating
  huge_blocks.replace(huge_blocks.find("block_size 8"), 12, "block_size 1024");
  EXPECT_NE(reason(huge_blocks).find("out of range"), std::string::npos);
  const std::size_t body = bytes.find("\n", bytes.find("blocks ")) + 1, block_bytes = 13 + 512 * 10;
  ASSERT_GE(bytes.size(), body + 2 * block_bytes);
  std::string repeated = bytes;  // the first block given twice
  repeated.replace(body + block_bytes, block_bytes, bytes.substr(body, block_bytes));
  EXPECT_NE(reason(repeated).find("block 1 of"), std::string::npos);
  EXPECT_NE(reason(repeated).find("out of index order or repeated"), std::string::npos);
  std::string fg255 = bytes;  // foreground byte 255 (254 is probability 1)
  fg255[body + 13 + 6] = static_cast<char>(255);
  EXPECT_NE(reason(fg255).find("voxel out of range"), std::string::npos);
  std::string no_resolution = bytes;
  no_resolution.replace(no_resolution.find("resolution_m"), 12, "resolution_x");
  EXPECT_NE(reason(no_resolution).find("header unreadable"), std::string::npos);
}

// The documented layout, byte for byte: block (1, -2, 3) flagged negative, its first voxel sdf_q -2, weight_q
// 0x0512, min_distance_mm 0x5678, foreground_q 200, rgb 1 2 3; every other voxel as constructed (sdf_q 32767,
// weight 0, no distance, foreground 127, black). A voxel turned negative on load sets the flag of its block.
TEST_F(TsdfIoTest, TheFileHoldsTheDocumentedBytes) {
  TsdfParams params = objectTsdfParams();
  params.block_size = 2;
  TsdfMap map(params);
  TsdfMap::SavedBlock block;
  block.index = Eigen::Vector3i(1, -2, 3);
  block.voxels.resize(8);
  block.has_negative = true;
  TsdfVoxel& v = block.voxels[0];
  v.sdf_q = -2;
  v.weight_q = 0x0512;  // 81.125 observations, under max_weight
  v.min_distance_mm = 0x5678;
  v.foreground_q = 200;
  v.rgb[0] = 1;
  v.rgb[1] = 2;
  v.rgb[2] = 3;
  map.loadBlocks({block});
  const fs::path path = dir_ / "one.tsdf";
  ASSERT_TRUE(saveTsdf(map, path.string()));
  const std::string bytes = readAll(path);
  const std::string header =
      "semexp_tsdf 1\nresolution_m 0.02\ntruncation_m 0.080000000000000002\nbehind_surface_m 0.040000000000000001\n"
      "behind_surface_quadratic_per_m 0\nfull_weight_depth_m 0\nforeground_prior 0.5\nforeground_prior_weight 0\n"
      "block_size 2\nmax_weight 100\nblocks 1\n";
  ASSERT_EQ(bytes.substr(0, header.size()), header);
  const std::uint8_t expected_block[] = {1, 0, 0, 0, 0xfe, 0xff, 0xff, 0xff, 3, 0, 0, 0, 1,
                                         0xfe, 0xff, 0x12, 0x05, 0x78, 0x56, 200, 1, 2, 3};
  const std::uint8_t untouched_voxel[] = {0xff, 0x7f, 0, 0, 0xff, 0xff, 127, 0, 0, 0};
  ASSERT_EQ(bytes.size(), header.size() + 13 + 8 * 10);
  for (std::size_t k = 0; k < sizeof(expected_block); ++k)
    EXPECT_EQ(static_cast<std::uint8_t>(bytes[header.size() + k]), expected_block[k]) << "byte " << k;
  for (std::size_t k = 0; k < 10; ++k)
    EXPECT_EQ(static_cast<std::uint8_t>(bytes[header.size() + 23 + k]), untouched_voxel[k]) << "voxel 1 byte " << k;
  // The flag cleared in the file: the negative voxel sets it again.
  std::string cleared = bytes;
  cleared[header.size() + 12] = 0;
  writeAll(dir_ / "cleared.tsdf", cleared);
  const auto loaded = loadTsdf((dir_ / "cleared.tsdf").string());
  ASSERT_TRUE(loaded);
  loaded->forEachBlock([](const Eigen::Vector3i&, const std::vector<TsdfVoxel>&, bool n) { EXPECT_TRUE(n); });
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
  // The index records the gate; the same gate gives the saved meshes (the same triangles) and the same index.
  ObjectMapConfig recorded;
  ASSERT_TRUE(readSavedMeshSettings((dir_ / "objects").string(), recorded, &error)) << error;
  EXPECT_EQ(recorded.mesh_max_sdf_std_m, 0.005);
  EXPECT_EQ(recorded.mesh_min_foreground, 0.5);
  EXPECT_EQ(recorded.mesh_fragment_gap_m, c.mesh_fragment_gap_m);
  EXPECT_EQ(recorded.depth_noise.s_per_m, c.depth_noise.s_per_m);
  ASSERT_EQ(remeshSavedObjects((dir_ / "objects").string(), (dir_ / "again").string(), recorded, &error), 2) << error;
  for (const std::string& name : meshes) {
    Mesh saved, again;
    ASSERT_TRUE(readPly((dir_ / "objects" / name).string(), saved));
    ASSERT_TRUE(readPly((dir_ / "again" / name).string(), again));
    ASSERT_GT(saved.triangles.size(), 200u) << name;
    EXPECT_TRUE(triangleSet(again) == triangleSet(saved)) << name;
  }
  EXPECT_EQ(readAll(dir_ / "again" / "objects.json"), readAll(dir_ / "objects" / "objects.json"));
  // A higher foreground bound keeps a part of each mesh, and the index records it.
  ObjectMapConfig strict = recorded;
  strict.mesh_min_foreground = 0.7;
  ASSERT_EQ(remeshSavedObjects((dir_ / "objects").string(), (dir_ / "strict").string(), strict, &error), 2) << error;
  for (const std::string& name : meshes) {
    Mesh saved, kept;
    ASSERT_TRUE(readPly((dir_ / "objects" / name).string(), saved));
    ASSERT_TRUE(readPly((dir_ / "strict" / name).string(), kept));
    EXPECT_GT(kept.triangles.size(), 0u) << name;
    EXPECT_LT(kept.triangles.size(), saved.triangles.size()) << name;
  }
  ObjectMapConfig strict_read;
  ASSERT_TRUE(readSavedMeshSettings((dir_ / "strict").string(), strict_read, &error)) << error;
  EXPECT_EQ(strict_read.mesh_min_foreground, 0.7);
  EXPECT_EQ(strict_read.mesh_max_sdf_std_m, 0.005);
  // Refused, with nothing written or deleted: the input as output, a directory holding another map's mesh,
  // an invalid gate.
  EXPECT_EQ(remeshSavedObjects((dir_ / "objects").string(), (dir_ / "objects" / ".").string(), strict, &error), -1);
  EXPECT_NE(error.find("output directory is the input"), std::string::npos) << error;
  writeAll(dir_ / "strict" / "object_99_chair.ply", "ply\n");
  EXPECT_EQ(remeshSavedObjects((dir_ / "objects").string(), (dir_ / "strict").string(), recorded, &error), -1);
  EXPECT_NE(error.find("object_99_chair.ply, a mesh of another map"), std::string::npos) << error;
  EXPECT_TRUE(fs::exists(dir_ / "strict" / "object_99_chair.ply"));
  strict.mesh_min_foreground = 0.4;
  EXPECT_EQ(remeshSavedObjects((dir_ / "objects").string(), (dir_ / "low").string(), strict, &error), -1);
  EXPECT_NE(error.find("object_map/mesh_min_foreground"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(dir_ / "low"));
  // A directory saved without TSDFs cannot be remeshed, and says why.
  c.save_tsdf = false;
  ObjectMap plain(c, ClassTable());
  fly(plain, 2);
  ASSERT_FALSE(plain.save((dir_ / "plain").string(), 1.0, &error).empty());
  EXPECT_EQ(remeshSavedObjects((dir_ / "plain").string(), (dir_ / "out").string(), c, &error), -1);
  EXPECT_NE(error.find("save_tsdf true"), std::string::npos) << error;
}

}  // namespace
