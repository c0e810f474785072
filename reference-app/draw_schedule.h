// When the app draws a frame: on demand. With a software rasteriser, drawing the same picture
// again and again took about 1.5 of the machine's 2 cores while the artist did nothing — the
// cores a session's merges, rebases and the other artists' processes need. A frame is drawn
// when something on screen changed: input (and a few frames after it, for ImGui's hover and
// active states to settle), the mesh, a session's version, cursors or peers, a message; and
// every frame while a stroke, a replay or a benchmark runs. Otherwise the loop sleeps in
// glfwWaitEventsTimeout, waking often enough in a session to take what the worker published.
#pragma once

class DrawSchedule {
 public:
  /** Frames drawn after input: ImGui shows a click or a hover one frame after the event. */
  static constexpr int kSettleFrames = 3;
  /** The longest sleep while the session may publish something (its cursors come at 20 Hz). */
  static constexpr double kSessionWakeSeconds = 1.0 / 60.0;
  /** The longest sleep otherwise: only --exit-after and the window's close wait on it. */
  static constexpr double kIdleWakeSeconds = 0.25;
  /** How often the session panel's running figures (bytes, latency) are redrawn. */
  static constexpr double kFigureRefreshSeconds = 0.5;

  /** Something on screen changed, or will once `frames` more frames are drawn. */
  void request(int frames = kSettleFrames) {
    if (frames > pending_) pending_ = frames;
  }
  /** Whether this frame is drawn; every frame is while `busy`. */
  bool take(bool busy) {
    if (pending_ > 0) {
      --pending_;
      return true;
    }
    return busy;
  }
  /** How long the loop may wait for events before the next frame: 0 when one is due. */
  double wait_seconds(bool busy, bool in_session) const {
    if (busy || pending_ > 0) return 0.0;
    return in_session ? kSessionWakeSeconds : kIdleWakeSeconds;
  }
  /** True every kFigureRefreshSeconds of `now`: time to redraw the running figures. */
  bool figures_due(double now) {
    if (now < figures_at_) return false;
    figures_at_ = now + kFigureRefreshSeconds;
    return true;
  }

 private:
  int pending_ = kSettleFrames;  // the first frames are drawn (READY follows the first)
  double figures_at_ = 0.0;
};
