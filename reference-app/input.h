// What the app does with input: the GLFW callbacks and the replay both call these, so a
// replayed session is the same code path as a person at the mouse.
#pragma once

struct InputHandlers {
  virtual ~InputHandlers() = default;
  virtual void on_cursor(double x, double y) = 0;
  virtual void on_button(int button, int action, int mods) = 0;
  virtual void on_key(int key, int action, int mods) = 0;
  virtual void on_scroll(double dy) = 0;
  /** Pen pressure 0..1 (GLFW 3.3 has none; the replay and a future XInput2 path set it). */
  virtual void on_pressure(float pressure) = 0;
  /** For the replay's `wait session`: true once this app holds a session's mesh. */
  virtual bool in_session() const = 0;
  /** For the replay's `wait version N`: the agreed version this app has applied (0 solo). */
  virtual unsigned long long session_version() const = 0;
};
