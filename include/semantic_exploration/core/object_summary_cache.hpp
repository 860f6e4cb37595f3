#pragma once
/// @file object_summary_cache.hpp
/// Each object's ObjectMap::summarize, kept until the object's TSDF changes
/// (TsdfMapT::revision()). The object map node publishes every object's
/// summary with every frame in lockstep runs; only the objects integrated
/// since (the visible ones) are summarised again.

#include <cstddef>
#include <cstdint>
#include <iterator>
#include <unordered_map>

#include "semantic_exploration/core/object_map.hpp"

namespace semexp {

class ObjectSummaryCache {
 public:
  /// @param d_obj_m  observed_fraction counts the surface seen from <= this, m
  explicit ObjectSummaryCache(double d_obj_m) : d_obj_m_(d_obj_m) {}

  /// map.summarize(object, d_obj_m), computed again only if the object's TSDF changed since the last call
  /// for its id. The reference stays valid until the next call of get() or prune().
  const TsdfSummary& get(const ObjectMap& map, const MappedObject& object) {
    Entry& e = entries_[object.id];
    if (!e.valid || e.revision != object.tsdf.revision()) {
      e.summary = map.summarize(object, d_obj_m_);
      e.revision = object.tsdf.revision();
      e.valid = true;
      ++computed_;
    }
    return e.summary;
  }
  /// Drops the entries of objects no longer in the map (merged away).
  void prune(const ObjectMap& map) {
    for (auto it = entries_.begin(); it != entries_.end();)
      it = map.object(it->first) ? std::next(it) : entries_.erase(it);
  }
  std::size_t size() const { return entries_.size(); }
  /// Summaries computed so far (the others came from the cache).
  std::size_t computed() const { return computed_; }

 private:
  struct Entry {
    bool valid = false;
    std::uint64_t revision = 0;
    TsdfSummary summary;
  };
  double d_obj_m_;
  std::unordered_map<std::uint32_t, Entry> entries_;
  std::size_t computed_ = 0;
};

}  // namespace semexp
