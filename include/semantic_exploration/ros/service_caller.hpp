#pragma once
/// @file service_caller.hpp
/// Service calls bounded in time, for a node that must not stall on a slow or
/// missing server (the planner's gain and history calls).
///
/// Every call runs on a worker thread with its own non-persistent client and
/// is given up after timeout_s (finding the service included). An abandoned
/// call keeps its own copy of request and response, so its late answer is
/// dropped with it; at most kMaxPendingCalls abandoned calls per service are
/// kept waiting, and a service that timed out is not called again until the
/// caller starts a new round (newRound()): waiting twice in one planning
/// iteration would only double the stall. A call that the service was found
/// for but that came back without an answer is made once more on a new
/// connection, within what is left of the same timeout_s, before it counts as
/// failed: under load a connection can lose the answer (two runs of one
/// deterministic mission parted there), and the planner's calls are queries.
/// roscpp does not tell that from a handler that refused the request (a bad
/// request is then sent twice). Failures are counted in the node's
/// DropCounter as service_timeout, service_failed or service_busy; calls made
/// again are logged (throttled) with a running count.

#include <ros/ros.h>

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "semantic_exploration/ros/node_common.hpp"

namespace semexp_ros {

class ServiceCaller {
 public:
  /// How a bounded call ended.
  enum class Result { kOk, kUnavailable, kFailed, kTimedOut, kBusy };

  /// Abandoned calls per service still waited for; beyond it the service is not called again until one ends.
  static constexpr int kMaxPendingCalls = 4;

  /// nh: service names are resolved relative to it. timeout_s: the longest a
  /// call may take, finding the service included, wall s (> 0).
  ServiceCaller(const ros::NodeHandle& nh, double timeout_s, DropCounter& drops);
  /// Joins abandoned calls (they end once roscpp has shut down and dropped their connections).
  ~ServiceCaller();
  ServiceCaller(const ServiceCaller&) = delete;
  ServiceCaller& operator=(const ServiceCaller&) = delete;

  /// Calls `service` with at most timeout_s for finding it and its answer. On
  /// kOk srv.response holds the answer; otherwise `why` says what happened
  /// (also counted and logged through the DropCounter).
  template <class Srv>
  Result call(const std::string& service, Srv& srv, std::string& why);

  /// Starts a new round: services that timed out in the last one are called again.
  void newRound() { timed_out_now_.clear(); }
  /// Forgets that `service` timed out in this round (a call outside the round, e.g. a resync).
  void forgetTimeout(const std::string& service) { timed_out_now_.erase(service); }
  double timeout_s() const { return timeout_s_; }
  /// Abandoned calls whose worker has not ended yet.
  std::size_t pending() const { return pending_calls_.size(); }

 private:
  struct CallState {
    std::mutex mutex;
    std::condition_variable done_cv;
    bool available = false;  ///< the service was found
    bool done = false;       ///< the worker has finished
    bool ok = false;         ///< the call returned an answer
  };
  /// A call given up after timeout_s whose worker has not ended yet.
  struct PendingCall {
    std::string service;
    std::shared_ptr<CallState> state;
    std::thread worker;
  };

  /// Joins the workers of abandoned calls that have ended.
  void reap();
  /// kBusy (with why) if `service` has too many abandoned calls, kTimedOut if it timed out in this round, else kOk.
  Result admit(const std::string& service, std::string& why);
  /// One try of call() on a new connection, after admit(), waiting at most timeout_s (wall s).
  template <class Srv>
  Result attempt(const std::string& service, Srv& srv, double timeout_s, bool last_try, std::string& why);
  /// Outcome of a call whose worker ended in time (done) or not; records timeouts and drops (a try without an
  /// answer only if it was the last).
  Result finish(const std::string& service, const std::shared_ptr<CallState>& state, bool done,
                std::thread&& worker, bool last_try, std::string& why);

  ros::NodeHandle nh_;
  double timeout_s_;
  DropCounter& drops_;
  std::vector<PendingCall> pending_calls_;
  /// Services that timed out in the current round (-> why).
  std::map<std::string, std::string> timed_out_now_;
  std::size_t retries_ = 0;  ///< calls made again after a first try without an answer
};

template <class Srv>
ServiceCaller::Result ServiceCaller::call(const std::string& service, Srv& srv, std::string& why) {
  const Result admitted = admit(service, why);
  if (admitted != Result::kOk) return admitted;
  const auto start = std::chrono::steady_clock::now();
  const Result first = attempt(service, srv, timeout_s_, false, why);
  if (first != Result::kFailed) return first;
  // The second try gets what the first left of timeout_s: a call never waits longer than one.
  const double left_s = timeout_s_ - std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (left_s <= 0.0) {  // no time left: it failed (a try this short would be reported as the service missing)
    drops_.drop("service_failed", why);
    return first;
  }
  ++retries_;
  ROS_WARN_THROTTLE(10.0, "%s without an answer; calling it once more (%zu calls made again so far)", why.c_str(),
                    retries_);
  return attempt(service, srv, left_s, true, why);
}

template <class Srv>
ServiceCaller::Result ServiceCaller::attempt(const std::string& service, Srv& srv, double timeout_s, bool last_try,
                                             std::string& why) {
  // The worker owns its client, request and response: a call abandoned here
  // may answer later into its own copy, which nobody reads. A fresh
  // non-persistent client per call finds a restarted service again and is
  // never used by two threads at once. It is built directly rather than
  // through the NodeHandle, which would keep a record of every client made
  // (one per call) and, used from a worker after shutdown, start roscpp again.
  auto state = std::make_shared<CallState>();
  auto request = std::make_shared<Srv>(srv);
  ros::ServiceClient client(nh_.resolveName(service), false, ros::M_string(), ros::service_traits::md5sum<Srv>());
  std::thread worker([state, request, client, timeout_s]() mutable {
    const bool available = client.waitForExistence(ros::Duration(timeout_s));
    {
      std::lock_guard<std::mutex> lock(state->mutex);
      state->available = available;
    }
    const bool ok = available && client.call(*request);
    {
      std::lock_guard<std::mutex> lock(state->mutex);
      state->ok = ok;
      state->done = true;
    }
    state->done_cv.notify_all();
  });
  bool done = false;
  {
    std::unique_lock<std::mutex> lock(state->mutex);
    done = state->done_cv.wait_for(lock, std::chrono::duration<double>(timeout_s), [&state] { return state->done; });
  }
  const Result result = finish(service, state, done, std::move(worker), last_try, why);
  if (result == Result::kOk) srv.response = std::move(request->response);
  return result;
}

}  // namespace semexp_ros
