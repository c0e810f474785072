// Helpers for the tests that run real sessions in this process over loopback sockets.
#pragma once

#include <chrono>
#include <string>
#include <thread>

#include "csculpt/peer/session.h"

namespace csculpt::peer::testing {

/// Options with short intervals (merge every 30 ms; heartbeat 50, evasive 200, expired 400).
inline SessionOptions fast_options(PeerId id, std::string name = "") {
  SessionOptions o;
  o.id = id;
  o.name = std::move(name);
  o.sync = Millis{30};
  o.membership = {Millis{50}, Millis{200}, Millis{400}};
  return o;
}

/// Polls `done` every 5 ms until it holds or `timeout` passes; whether it held.
template <class Done>
bool wait_until(Done&& done, Millis timeout = Millis{5000}) {
  const auto deadline = Clock::now() + timeout;
  while (Clock::now() < deadline) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return done();
}

}  // namespace csculpt::peer::testing
