#include "semantic_exploration/core/depth_history.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace semexp {

DepthHistory::DepthHistory(const DepthHistoryConfig& config, const Bounds& bounds, const PinholeCamera& camera)
    : config_(config), bounds_(bounds), camera_(camera) {
  config_.validate();
  bounds_.validate();
  camera_.validate();
  grid_.width = config_.width;
  grid_.height = config_.height;
  grid_.vfov_rad = camera_.vfov_rad();
  grid_.validate("depth_history/");
  const Eigen::Vector3d n = (bounds_.size_m() / config_.cell_size_m).array().ceil();
  cells_ = n.cast<int>().cwiseMax(1);
  rays_C_.resize(static_cast<std::size_t>(camera_.width) * camera_.height);
  for (int v = 0; v < camera_.height; ++v)
    for (int u = 0; u < camera_.width; ++u)
      rays_C_[static_cast<std::size_t>(v) * camera_.width + u] =
          camera_.ray_C(static_cast<float>(u), static_cast<float>(v)).cast<double>().normalized();
}

bool DepthHistory::cell_index(const Eigen::Vector3d& p_W, Eigen::Vector3i& index) const {
  if (!p_W.allFinite() || !bounds_.contains(p_W)) return false;
  const Eigen::Vector3d f = ((p_W - bounds_.min_m) / config_.cell_size_m).array().floor();
  // The upper bound face belongs to the last cell.
  index = f.cast<int>().cwiseMin(cells_ - Eigen::Vector3i::Ones()).cwiseMax(0);
  return true;
}

Eigen::Vector3d DepthHistory::cell_center(const Eigen::Vector3i& index) const {
  return bounds_.min_m + (index.cast<double>().array() + 0.5).matrix() * config_.cell_size_m;
}

std::int64_t DepthHistory::key(const Eigen::Vector3i& i) const {
  return (static_cast<std::int64_t>(i.z()) * cells_.y() + i.y()) * cells_.x() + i.x();
}

Eigen::Vector3i DepthHistory::unkey(std::int64_t k) const {
  const int x = static_cast<int>(k % cells_.x());
  k /= cells_.x();
  const int y = static_cast<int>(k % cells_.y());
  return {x, y, static_cast<int>(k / cells_.y())};
}

std::size_t DepthHistory::integrate(const cv::Mat& depth, const Eigen::Isometry3d& T_WC) {
  if (depth.type() != CV_32FC1 && depth.type() != CV_16UC1)
    throw std::invalid_argument("DepthHistory::integrate: depth must be CV_32FC1 (m) or CV_16UC1 (mm)");
  if (depth.cols != camera_.width || depth.rows != camera_.height)
    throw std::invalid_argument("DepthHistory::integrate: depth is " + std::to_string(depth.cols) + "x" +
                                std::to_string(depth.rows) + ", camera is " + std::to_string(camera_.width) +
                                "x" + std::to_string(camera_.height));
  Eigen::Vector3i cell;
  if (!cell_index(T_WC.translation(), cell)) return 0;
  const Eigen::Matrix3d R_WC = T_WC.linear();
  std::vector<std::uint8_t>* image = nullptr;  // allocated on the first invalid pixel
  std::size_t invalid = 0;
  const bool mm = depth.type() == CV_16UC1;
  for (int v = 0; v < depth.rows; ++v) {
    for (int u = 0; u < depth.cols; ++u) {
      const float d_m = mm ? 0.001f * depth.at<std::uint16_t>(v, u) : depth.at<float>(v, u);
      if (is_valid_depth(d_m, camera_)) continue;
      ++invalid;
      const Eigen::Vector3d dir_W = R_WC * rays_C_[static_cast<std::size_t>(v) * camera_.width + u];
      int gu = 0, gv = 0;
      if (!grid_.pixel(dir_W, gu, gv)) continue;  // outside the image's elevation band
      if (image == nullptr) {
        auto& img = images_[key(cell)];
        if (img.empty()) img.assign(static_cast<std::size_t>(grid_.width) * grid_.height, 1);
        image = &img;
      }
      (*image)[static_cast<std::size_t>(gv) * grid_.width + gu] = 0;
    }
  }
  return invalid;
}

std::vector<std::uint8_t> DepthHistory::mask(const Eigen::Vector3d& p_W) const {
  Eigen::Vector3i cell;
  if (cell_index(p_W, cell)) {
    const auto it = images_.find(key(cell));
    if (it != images_.end()) return it->second;
  }
  return std::vector<std::uint8_t>(static_cast<std::size_t>(grid_.width) * grid_.height, 1);
}

std::vector<std::vector<std::uint8_t>> DepthHistory::masks(const std::vector<Eigen::Vector3d>& positions_W) const {
  std::vector<std::vector<std::uint8_t>> out;
  out.reserve(positions_W.size());
  for (const auto& p : positions_W) out.push_back(mask(p));
  return out;
}

std::vector<DepthHistory::InvalidCell> DepthHistory::invalid_cells() const {
  std::vector<InvalidCell> out;
  for (const auto& kv : images_) {
    const int zeros = static_cast<int>(std::count(kv.second.begin(), kv.second.end(), std::uint8_t{0}));
    if (zeros > 0) out.push_back({cell_center(unkey(kv.first)), zeros});
  }
  // Deterministic order for markers and tests.
  std::sort(out.begin(), out.end(), [](const InvalidCell& a, const InvalidCell& b) {
    return std::lexicographical_compare(a.center_W.data(), a.center_W.data() + 3, b.center_W.data(),
                                        b.center_W.data() + 3);
  });
  return out;
}

}  // namespace semexp
