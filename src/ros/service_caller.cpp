#include "semantic_exploration/ros/service_caller.hpp"

#include <algorithm>

namespace semexp_ros {

ServiceCaller::ServiceCaller(const ros::NodeHandle& nh, double timeout_s, DropCounter& drops)
    : nh_(nh), timeout_s_(timeout_s), drops_(drops) {
  // ros::Duration throws past its range, inside a worker thread: keep it finite.
  if (!(timeout_s_ > 0 && timeout_s_ <= 3600))
    throw semexp::ConfigError("planner/service_timeout_s", "must be in (0, 3600] s");
}

ServiceCaller::~ServiceCaller() {
  for (auto& c : pending_calls_)
    if (c.worker.joinable()) c.worker.join();
}

void ServiceCaller::reap() {
  for (auto it = pending_calls_.begin(); it != pending_calls_.end();) {
    bool done = false;
    {
      std::lock_guard<std::mutex> lock(it->state->mutex);
      done = it->state->done;
    }
    if (!done) {
      ++it;
      continue;
    }
    it->worker.join();
    it = pending_calls_.erase(it);
  }
}

ServiceCaller::Result ServiceCaller::admit(const std::string& service, std::string& why) {
  reap();
  const auto earlier = timed_out_now_.find(service);
  if (earlier != timed_out_now_.end()) {
    why = earlier->second;
    return Result::kTimedOut;
  }
  const auto pending = std::count_if(pending_calls_.begin(), pending_calls_.end(),
                                     [&service](const PendingCall& c) { return c.service == service; });
  if (pending >= kMaxPendingCalls) {
    char buf[256];
    std::snprintf(buf, sizeof(buf), "service %s not called: %d earlier calls are still unanswered", service.c_str(),
                  static_cast<int>(pending));
    why = buf;
    drops_.drop("service_busy", why);
    return Result::kBusy;
  }
  return Result::kOk;
}

ServiceCaller::Result ServiceCaller::finish(const std::string& service, const std::shared_ptr<CallState>& state,
                                            bool done, std::thread&& worker, bool last_try, std::string& why) {
  bool available = false, ok = false;
  {
    std::lock_guard<std::mutex> lock(state->mutex);
    available = state->available;
    ok = state->ok;
  }
  char buf[256];
  if (done) {
    worker.join();
    if (ok) return Result::kOk;
    if (!available) {
      std::snprintf(buf, sizeof(buf), "service %s timed out after %.1f s (not available)", service.c_str(),
                    timeout_s_);
      why = buf;
      timed_out_now_[service] = why;
      drops_.drop("service_timeout", why);
      return Result::kUnavailable;
    }
    why = "service " + service + " failed";
    if (last_try) drops_.drop("service_failed", why);
    return Result::kFailed;
  }
  std::snprintf(buf, sizeof(buf), "service %s timed out after %.1f s%s", service.c_str(), timeout_s_,
                available ? " (no answer)" : " (not available)");
  why = buf;
  pending_calls_.push_back(PendingCall{service, state, std::move(worker)});
  timed_out_now_[service] = why;
  drops_.drop("service_timeout", why);
  return Result::kTimedOut;
}

}  // namespace semexp_ros
