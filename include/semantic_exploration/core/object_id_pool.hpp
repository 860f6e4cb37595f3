#pragma once
/// @file object_id_pool.hpp
/// Object ids of the object map: 16-bit (object-id images are 16UC1), so they
/// must be reused, or a long run stops creating objects once 65535 ids were
/// ever taken (one candidate per frame that ends up empty does that in 1.8 h
/// at 10 Hz).

#include <cstdint>
#include <deque>
#include <utility>
#include <vector>

namespace semexp {

/// Hands out ids 1 .. max_id. An id released before anyone saw it (a
/// candidate erased in the frame that created it) is reused at once. An id
/// that was published (an object merged into another) may still be named by
/// a detection matched against an older render, so it is reused only
/// reuse_after_frames frames after its release, and only once no fresh id is
/// left.
class ObjectIdPool {
 public:
  /// Frames a published id rests before reuse: 10 s at 10 Hz, far longer than
  /// a detection can be in flight between instance_matching and object_map.
  static constexpr std::uint64_t kReuseAfterFrames = 100;

  explicit ObjectIdPool(std::uint32_t max_id = 65535, std::uint64_t reuse_after_frames = kReuseAfterFrames)
      : max_id_(max_id), reuse_after_frames_(reuse_after_frames) {}

  /// A free id at frame `frame` (a counter that grows by one per frame), 0 if none is free.
  std::uint32_t acquire(std::uint64_t frame) {
    if (!unpublished_.empty()) {
      const std::uint32_t id = unpublished_.back();
      unpublished_.pop_back();
      return id;
    }
    if (next_ <= max_id_) return next_++;
    if (!released_.empty() && frame >= released_.front().second + reuse_after_frames_) {
      const std::uint32_t id = released_.front().first;
      released_.pop_front();
      return id;
    }
    return 0;
  }
  /// Gives back an id nobody saw (reusable at once).
  void releaseUnpublished(std::uint32_t id) { unpublished_.push_back(id); }
  /// Gives back a published id at frame `frame` (reusable reuse_after_frames later).
  void release(std::uint32_t id, std::uint64_t frame) { released_.emplace_back(id, frame); }

 private:
  std::uint32_t max_id_;
  std::uint64_t reuse_after_frames_;
  std::uint32_t next_ = 1;                                       ///< lowest id never handed out
  std::vector<std::uint32_t> unpublished_;                       ///< reusable now
  std::deque<std::pair<std::uint32_t, std::uint64_t>> released_;  ///< (id, frame of release), oldest first
};

}  // namespace semexp
