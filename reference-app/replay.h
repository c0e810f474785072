// --replay FILE: input events, one per line, fed through InputHandlers frame by frame.
//   move X Y                 cursor to window pixel (X, Y)
//   press|release BUTTON [shift] [ctrl] [alt]     BUTTON: left, right, middle
//   key NAME [shift] [ctrl] [alt]                 press and release (keydown/keyup: one of them)
//   pressure P               pen pressure 0..1 from now on
//   scroll DY                wheel steps (positive: zoom in)
//   wait N                   let N frames pass
//   wait session             until the app hosts or has joined a session (a script's sync point)
//   wait version N           until the app has applied the session's version N (another one)
//   # comment
// NAME: a-z, 0-9, kp0-kp9, f1-f12, tab, escape, space, "[", "]", "-", "=".
// Deterministic: the events depend on frame counts only, never on time.
#pragma once

#include <string>
#include <vector>

#include "input.h"

class ReplayPlayer {
 public:
  bool load(const std::string& path, std::string& error);
  /** Runs this frame's events (up to the next wait). */
  void step(InputHandlers& input);
  bool active() const { return loaded_ && !finished(); }
  bool finished() const {
    return next_ >= events_.size() && waiting_ == 0 && !waiting_for_session_ &&
           waiting_for_version_ == 0;
  }
  bool loaded() const { return loaded_; }
  bool waiting_for_session() const { return waiting_for_session_; }

 private:
  enum class Kind {
    move,
    press,
    release,
    key,
    key_down,
    key_up,
    pressure,
    scroll,
    wait,
    wait_session,
    wait_version
  };
  struct Event {
    Kind kind;
    double x = 0, y = 0;
    int code = 0;  // button, key or frame count
    int mods = 0;
  };
  std::vector<Event> events_;
  size_t next_ = 0;
  int waiting_ = 0;
  bool waiting_for_session_ = false;
  unsigned long long waiting_for_version_ = 0;
  bool loaded_ = false;
};

/** GLFW key code of a replay key name, or -1. */
int key_from_name(const std::string& name);
