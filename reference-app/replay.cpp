#include "replay.h"

#include <GLFW/glfw3.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

int key_from_name(const std::string& name) {
  if (name.size() == 1) {
    const char c = name[0];
    if (c >= 'a' && c <= 'z') return GLFW_KEY_A + (c - 'a');
    if (c >= '0' && c <= '9') return GLFW_KEY_0 + (c - '0');
    if (c == '[') return GLFW_KEY_LEFT_BRACKET;
    if (c == ']') return GLFW_KEY_RIGHT_BRACKET;
    if (c == '-') return GLFW_KEY_MINUS;
    if (c == '=') return GLFW_KEY_EQUAL;
  }
  if (name.size() == 3 && name.rfind("kp", 0) == 0 && name[2] >= '0' && name[2] <= '9')
    return GLFW_KEY_KP_0 + (name[2] - '0');
  if (name.size() >= 2 && name[0] == 'f') {
    const int n = std::atoi(name.c_str() + 1);
    if (n >= 1 && n <= 12) return GLFW_KEY_F1 + n - 1;
  }
  if (name == "tab") return GLFW_KEY_TAB;
  if (name == "escape") return GLFW_KEY_ESCAPE;
  if (name == "space") return GLFW_KEY_SPACE;
  return -1;
}

bool ReplayPlayer::load(const std::string& path, std::string& error) {
  std::ifstream file(path);
  if (!file) {
    error = "cannot read the replay file " + path;
    return false;
  }
  events_.clear();
  std::string line;
  for (int number = 1; std::getline(file, line); ++number) {
    std::istringstream words(line);
    std::string verb;
    if (!(words >> verb) || verb[0] == '#') continue;
    Event e{Kind::wait};
    bool ok = true;
    auto read_mods = [&] {
      for (std::string mod; words >> mod;) {
        if (mod == "shift")
          e.mods |= GLFW_MOD_SHIFT;
        else if (mod == "ctrl")
          e.mods |= GLFW_MOD_CONTROL;
        else if (mod == "alt")
          e.mods |= GLFW_MOD_ALT;
        else
          ok = false;
      }
    };
    if (verb == "move") {
      e.kind = Kind::move;
      ok = static_cast<bool>(words >> e.x >> e.y);
    } else if (verb == "press" || verb == "release") {
      e.kind = verb == "press" ? Kind::press : Kind::release;
      std::string button;
      words >> button;
      e.code = button == "left"     ? GLFW_MOUSE_BUTTON_LEFT
               : button == "right"  ? GLFW_MOUSE_BUTTON_RIGHT
               : button == "middle" ? GLFW_MOUSE_BUTTON_MIDDLE
                                    : -1;
      ok = e.code >= 0;
      read_mods();
    } else if (verb == "key" || verb == "keydown" || verb == "keyup") {
      e.kind = verb == "key" ? Kind::key : verb == "keydown" ? Kind::key_down : Kind::key_up;
      std::string name;
      words >> name;
      e.code = key_from_name(name);
      ok = e.code >= 0;
      read_mods();
    } else if (verb == "pressure") {
      e.kind = Kind::pressure;
      ok = static_cast<bool>(words >> e.x) && e.x >= 0 && e.x <= 1;
    } else if (verb == "scroll") {
      e.kind = Kind::scroll;
      ok = static_cast<bool>(words >> e.y);
    } else if (verb == "wait") {
      std::string what;
      words >> what;
      if (what == "session") {
        e.kind = Kind::wait_session;
      } else if (what == "version") {
        e.kind = Kind::wait_version;
        ok = static_cast<bool>(words >> e.code) && e.code >= 1;
      } else {
        e.kind = Kind::wait;
        std::istringstream count(what);
        ok = static_cast<bool>(count >> e.code) && e.code >= 1;
      }
    } else {
      ok = false;
    }
    if (!ok) {
      error = path + ":" + std::to_string(number) + ": cannot read \"" + line + "\"";
      return false;
    }
    events_.push_back(e);
  }
  next_ = 0;
  waiting_ = 0;
  loaded_ = true;
  return true;
}

void ReplayPlayer::step(InputHandlers& input) {
  if (waiting_for_session_ && !input.in_session()) return;
  waiting_for_session_ = false;
  if (waiting_for_version_ > 0 && input.session_version() < waiting_for_version_) return;
  waiting_for_version_ = 0;
  if (waiting_ > 0 && --waiting_ > 0) return;
  while (next_ < events_.size()) {
    const Event& e = events_[next_++];
    switch (e.kind) {
      case Kind::move:
        input.on_cursor(e.x, e.y);
        break;
      case Kind::press:
        input.on_button(e.code, GLFW_PRESS, e.mods);
        break;
      case Kind::release:
        input.on_button(e.code, GLFW_RELEASE, e.mods);
        break;
      case Kind::key:
        input.on_key(e.code, GLFW_PRESS, e.mods);
        input.on_key(e.code, GLFW_RELEASE, e.mods);
        break;
      case Kind::key_down:
        input.on_key(e.code, GLFW_PRESS, e.mods);
        break;
      case Kind::key_up:
        input.on_key(e.code, GLFW_RELEASE, e.mods);
        break;
      case Kind::pressure:
        input.on_pressure(static_cast<float>(e.x));
        break;
      case Kind::scroll:
        input.on_scroll(e.y);
        break;
      case Kind::wait:
        waiting_ = e.code;
        return;
      case Kind::wait_session:
        waiting_for_session_ = true;
        return;
      case Kind::wait_version:
        waiting_for_version_ = static_cast<unsigned long long>(e.code);
        return;
    }
  }
}
