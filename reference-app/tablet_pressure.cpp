#include "tablet_pressure.h"

#include <GLFW/glfw3.h>

#include <algorithm>
#include <vector>

#if CSCULPT_APP_XINPUT2
#include <X11/Xlib.h>
#include <X11/extensions/XInput2.h>

// GLFW's X11 accessors (glfw3native.h declares them, but includes Xrandr's headers with them).
extern "C" Display* glfwGetX11Display(void);
extern "C" Window glfwGetX11Window(GLFWwindow* window);
#endif

#if CSCULPT_APP_XINPUT2

struct TabletPressure::X {
  struct Pen {
    int device;
    int valuator;  // the pressure valuator's number
    double min, max;
  };
  Display* display = nullptr;
  int opcode = 0;
  std::vector<Pen> pens;
  ~X() {
    if (display) XCloseDisplay(display);
  }
  const Pen* pen(int device) const {
    for (const Pen& p : pens)
      if (p.device == device) return &p;
    return nullptr;
  }
  void find_pens();
  std::optional<float> pressure_of(const XIDeviceEvent& e) const;
};

// Every device (a tablet's stylus and eraser are separate slaves) with a pressure valuator.
void TabletPressure::X::find_pens() {
  const Atom pressure = XInternAtom(display, "Abs Pressure", True);
  if (pressure == None) return;  // no driver ever named one: no tablet
  int count = 0;
  XIDeviceInfo* devices = XIQueryDevice(display, XIAllDevices, &count);
  for (int d = 0; d < count; ++d) {
    const XIDeviceInfo& info = devices[d];
    if (info.use != XISlavePointer && info.use != XIFloatingSlave) continue;
    for (int c = 0; c < info.num_classes; ++c) {
      if (info.classes[c]->type != XIValuatorClass) continue;
      const auto* v = reinterpret_cast<const XIValuatorClassInfo*>(info.classes[c]);
      if (v->label == pressure && v->max > v->min)
        pens.push_back({info.deviceid, v->number, v->min, v->max});
    }
  }
  XIFreeDeviceInfo(devices);
}

// The event's valuators are packed: the pressure's value is at the count of set bits below it.
std::optional<float> TabletPressure::X::pressure_of(const XIDeviceEvent& e) const {
  const Pen* p = pen(e.deviceid);
  if (!p || !XIMaskIsSet(e.valuators.mask, p->valuator)) return std::nullopt;
  int index = 0;
  for (int bit = 0; bit < p->valuator; ++bit) index += XIMaskIsSet(e.valuators.mask, bit) ? 1 : 0;
  const double value = (e.valuators.values[index] - p->min) / (p->max - p->min);
  return static_cast<float>(std::clamp(value, 0.0, 1.0));
}

TabletPressure::TabletPressure() = default;
TabletPressure::~TabletPressure() = default;

bool TabletPressure::open(GLFWwindow* window, std::string& why) {
  Display* glfw_display = glfwGetX11Display();
  if (!glfw_display) {
    why = "not an X11 window";
    return false;
  }
  auto x = std::make_unique<X>();
  x->display = XOpenDisplay(DisplayString(glfw_display));
  int event = 0, error = 0, major = 2, minor = 0;
  if (!x->display || !XQueryExtension(x->display, "XInputExtension", &x->opcode, &event, &error) ||
      XIQueryVersion(x->display, &major, &minor) != Success) {
    why = "the X server has no XInput2";
    return false;
  }
  x->find_pens();
  if (x->pens.empty()) {
    why = "no tablet (no device reports pressure)";
    return false;
  }
  unsigned char bits[XIMaskLen(XI_LASTEVENT)] = {};
  XISetMask(bits, XI_Motion);
  XISetMask(bits, XI_ButtonPress);
  std::vector<XIEventMask> masks;
  for (const X::Pen& p : x->pens) masks.push_back({p.device, sizeof bits, bits});
  XISelectEvents(x->display, glfwGetX11Window(window), masks.data(),
                 static_cast<int>(masks.size()));
  XFlush(x->display);
  x_ = std::move(x);
  return true;
}

int TabletPressure::tablets() const {
  return x_ ? static_cast<int>(x_->pens.size()) : 0;
}

std::optional<float> TabletPressure::poll() {
  if (!x_) return std::nullopt;
  std::optional<float> latest;
  while (XPending(x_->display) > 0) {
    XEvent event;
    XNextEvent(x_->display, &event);
    XGenericEventCookie& cookie = event.xcookie;
    if (cookie.type != GenericEvent || cookie.extension != x_->opcode ||
        !XGetEventData(x_->display, &cookie))
      continue;
    if (cookie.evtype == XI_Motion || cookie.evtype == XI_ButtonPress)
      if (auto p = x_->pressure_of(*static_cast<const XIDeviceEvent*>(cookie.data))) latest = p;
    XFreeEventData(x_->display, &cookie);
  }
  return latest;
}

#else  // built without X11/XInput2 headers

struct TabletPressure::X {};
TabletPressure::TabletPressure() = default;
TabletPressure::~TabletPressure() = default;

bool TabletPressure::open(GLFWwindow*, std::string& why) {
  why = "built without XInput2 (Debian: libxi-dev)";
  return false;
}

int TabletPressure::tablets() const {
  return 0;
}

std::optional<float> TabletPressure::poll() {
  return std::nullopt;
}

#endif
