// Pen pressure from a graphics tablet. GLFW 3.3 has no pressure API, so the app reads it from
// XInput2 itself: a second connection to the X server selects motion and button events on the
// app's window for every device with an "Abs Pressure" valuator (X delivers a window's events
// to every client that selected them, so GLFW's own input is untouched), and each frame takes
// the latest pressure, scaled to 0..1. Without a tablet, X11 or XInput2 it reports nothing and
// the brushes use full pressure (or what a --replay says).
#pragma once

#include <memory>
#include <optional>
#include <string>

struct GLFWwindow;

class TabletPressure {
 public:
  TabletPressure();
  ~TabletPressure();
  TabletPressure(const TabletPressure&) = delete;
  TabletPressure& operator=(const TabletPressure&) = delete;

  /** Looks for tablets and listens on `window`; false (with `why`) when there is no way to. */
  bool open(GLFWwindow* window, std::string& why);
  /** How many pressure-sensitive devices were found. */
  int tablets() const;
  /** The latest pressure reported since the last call, if any. */
  std::optional<float> poll();

 private:
  struct X;  // the X connection and the devices' pressure valuators
  std::unique_ptr<X> x_;
};
