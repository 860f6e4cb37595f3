// Saving: every file is replaced atomically (a failed write leaves the previous
// file and no temporary file), write errors are reported, /dev/full behind a
// symlink is refused, and stale object meshes go.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "semantic_exploration/core/atomic_file.hpp"
#include "semantic_exploration/core/marching_cubes.hpp"
#include "semantic_exploration/core/object_map.hpp"
#include "semantic_exploration/core/occupancy_map.hpp"
#include "semexp_test/cameras.hpp"
#include "semexp_test/rendering.hpp"
#include "semexp_test/temp_dir.hpp"

using namespace semexp;
using namespace semexp_test;
namespace fs = std::filesystem;

namespace {

std::string readAll(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

void writeText(const fs::path& p, const std::string& s) { std::ofstream(p, std::ios::binary) << s; }

using SaveTest = TempDirTest;

/// While alive, files this process writes may not grow past `bytes` (writes
/// then fail with EFBIG, as on a full device).
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    old_handler_ = ::signal(SIGXFSZ, SIG_IGN);
    ::getrlimit(RLIMIT_FSIZE, &old_);
    rlimit l = old_;
    l.rlim_cur = bytes;
    ::setrlimit(RLIMIT_FSIZE, &l);
  }
  ~FileSizeLimit() {
    ::setrlimit(RLIMIT_FSIZE, &old_);
    ::signal(SIGXFSZ, old_handler_);
  }

 private:
  rlimit old_{};
  sighandler_t old_handler_;
};

/// One chair (a sphere) seen once by a 64 x 48 camera.
ObjectMap oneChair() {
  const PinholeCamera cam = tinyCamera();
  ObjectMap map{ObjectMapConfig(), ClassTable()};
  const Sphere chair(Eigen::Vector3d(0.0, 0.0, 1.0), 0.25);
  const Eigen::Isometry3d T_WC = lookAt(Eigen::Vector3d(-0.9, 0.0, 1.0), chair.centre);
  cv::Mat depth, labels;
  renderShapes(cam, T_WC, {&chair}, depth, labels);
  map.integrateFrame(cam, T_WC, depth, cv::Mat(), labels, {{1, 0, 1}});
  return map;
}

}  // namespace

TEST_F(SaveTest, WritesAndReplacesWithoutTemporaryFiles) {
  const fs::path p = dir_ / "a.txt";
  writeFileAtomically(p.string(), [](std::ostream& f) { f << "first"; });
  writeFileAtomically(p.string(), [](std::ostream& f) { f << "second"; });
  EXPECT_EQ(readAll(p), "second");
  EXPECT_EQ(listing(), std::vector<std::string>{"a.txt"});
  // Readable like any file the user creates (not mkstemp's 0600).
  EXPECT_NE(fs::status(p).permissions() & fs::perms::others_read, fs::perms::none);
}

TEST_F(SaveTest, AFailedWriteLeavesThePreviousFile) {
  const fs::path p = dir_ / "a.txt";
  writeText(p, "previous");
  EXPECT_THROW(writeFileAtomically(p.string(), [](std::ostream& f) {
                 f << "half";
                 throw std::runtime_error("serialiser failed");
               }),
               std::runtime_error);
  EXPECT_EQ(readAll(p), "previous");
  EXPECT_EQ(listing(), std::vector<std::string>{"a.txt"});
  {
    FileSizeLimit full(1000);  // the device is full after 1000 bytes
    try {
      writeFileAtomically(p.string(), [](std::ostream& f) { f << std::string(100000, 'x'); });
      ADD_FAILURE() << "a write past the file size limit was reported as success";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("previous file is unchanged"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(readAll(p), "previous");
  EXPECT_EQ(listing(), std::vector<std::string>{"a.txt"});
}

TEST_F(SaveTest, SymlinksAreFollowedButDevicesRefused) {
  writeText(dir_ / "real.txt", "old");
  fs::create_symlink(dir_ / "real.txt", dir_ / "link.txt");
  writeFileAtomically((dir_ / "link.txt").string(), [](std::ostream& f) { f << "new"; });
  EXPECT_TRUE(fs::is_symlink(dir_ / "link.txt"));
  EXPECT_EQ(readAll(dir_ / "real.txt"), "new");
  fs::create_symlink("/dev/full", dir_ / "full.txt");
  try {
    writeFileAtomically((dir_ / "full.txt").string(), [](std::ostream& f) { f << "data"; });
    ADD_FAILURE() << "a write to /dev/full was reported as success";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/full is not a regular file"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_symlink(dir_ / "full.txt"));
  EXPECT_EQ(listing(), (std::vector<std::string>{"full.txt", "link.txt", "real.txt"}));
}

TEST_F(SaveTest, BackgroundMapFilesSurviveAFullDevice) {
  OccupancyMap map{BackgroundMapConfig(), Bounds()};
  map.markFreeSphere(Eigen::Vector3d(0.0, 0.0, 1.0), 0.5);
  const std::string own = (dir_ / "map.semexpmap").string(), bt = (dir_ / "map.bt").string(),
                    ply = (dir_ / "occupied.ply").string();
  map.save(own);
  map.exportOctomap(bt);
  map.exportOccupiedPly(ply);
  const std::string own0 = readAll(own), bt0 = readAll(bt), ply0 = readAll(ply);
  ASSERT_GT(own0.size(), 10000u);
  ASSERT_GT(bt0.size(), 1000u);
  map.markFreeSphere(Eigen::Vector3d(1.0, 0.0, 1.0), 0.5);  // something new to save
  {
    FileSizeLimit full(512);
    EXPECT_THROW(map.save(own), std::runtime_error);
    EXPECT_THROW(map.exportOctomap(bt), std::runtime_error);
  }
  EXPECT_EQ(readAll(own), own0);
  EXPECT_EQ(readAll(bt), bt0);
  EXPECT_EQ(readAll(ply), ply0);
  EXPECT_EQ(listing(), (std::vector<std::string>{"map.bt", "map.semexpmap", "occupied.ply"}));
}

TEST_F(SaveTest, ObjectMapReportsAFailedIndexAndDropsStaleMeshes) {
  const ObjectMap map = oneChair();
  ASSERT_EQ(map.objects().size(), 1u);
  // An earlier save left the mesh of an object that is gone since (merged away).
  writeText(dir_ / "object_7_chair.ply", "stale");
  writeText(dir_ / "notes.ply", "not ours");
  std::string error;
  auto files = map.save(dir_.string(), 1.0, &error);
  EXPECT_EQ(error, "");
  EXPECT_EQ(listing(), (std::vector<std::string>{"notes.ply", "object_1_chair.ply", "objects.json"}));
  const std::string index0 = readAll(dir_ / "objects.json");
  // objects.json behind a symlink to /dev/full: the save fails, and says so.
  fs::remove(dir_ / "objects.json");
  fs::create_symlink("/dev/full", dir_ / "objects.json");
  files = map.save(dir_.string(), 1.0, &error);
  EXPECT_NE(error.find("objects.json"), std::string::npos) << error;
  EXPECT_NE(error.find("not a regular file"), std::string::npos) << error;
  EXPECT_EQ(std::count(files.begin(), files.end(), (dir_ / "objects.json").string()), 0);
  // A full device while the index is written: the previous index stays.
  fs::remove(dir_ / "objects.json");
  writeText(dir_ / "objects.json", index0);
  {
    FileSizeLimit full(100);  // the mesh and the index are both larger
    error.clear();
    map.save(dir_.string(), 1.0, &error);
  }
  EXPECT_NE(error.find("previous file is unchanged"), std::string::npos) << error;
  EXPECT_EQ(readAll(dir_ / "objects.json"), index0);
  EXPECT_EQ(listing(), (std::vector<std::string>{"notes.ply", "object_1_chair.ply", "objects.json"}));
}
