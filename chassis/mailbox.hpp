#pragma once
// A one-slot mailbox between threads: the writer replaces the latest value, the reader takes it
// without ever waiting (try_lock; when the writer holds the lock the reader comes back next
// tick). This is how the control loop publishes to the chassis without blocking it.
#include <cstdint>
#include <mutex>

#include "chassis/clock.hpp"
#include "chassis/command.hpp"

namespace mppi::chassis {

template <class T>
class Mailbox {
 public:
  void put(const T& value) {
    std::lock_guard<std::mutex> lock(mutex_);
    value_ = value;
    ++sequence_;
  }
  // Copies the value into *out if there is one newer than *last_seen and the lock is free at
  // once; never blocks. Returns whether *out was written.
  bool try_take(T* out, std::uint64_t* last_seen) {
    std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock() || sequence_ == *last_seen) return false;
    *out = value_;
    *last_seen = sequence_;
    return true;
  }

 private:
  std::mutex mutex_;
  T value_{};
  std::uint64_t sequence_ = 0;
};

// A command with the time it was published (the chassis' clock).
struct StampedCommand {
  Command command;
  Time published{0};
};
using CommandMailbox = Mailbox<StampedCommand>;

}  // namespace mppi::chassis
