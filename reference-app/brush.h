// Brush settings as the artist sets them in the panel (and through the shortcut keys).
#pragma once

#include <glm/vec3.hpp>

#include <array>

enum class BrushKind { draw, grab, inflate, smooth, flatten, crease, pinch, twist, paint };
enum class PaintChannel { albedo, roughness, metallic };
enum class Falloff { smooth, sphere, linear, sharp, constant };

inline constexpr std::array kBrushNames = {"Draw",   "Grab",  "Inflate", "Smooth", "Flatten",
                                           "Crease", "Pinch", "Twist",   "Paint"};
inline constexpr std::array kFalloffNames = {"Smooth", "Sphere", "Linear", "Sharp", "Constant"};
inline constexpr std::array kPaintChannelNames = {"Albedo", "Roughness", "Metallic"};

struct BrushSettings {
  BrushKind kind = BrushKind::draw;
  float radius_pixels = 50.f;  // screen space: the same on screen at any zoom
  float strength = 0.5f;       // 0..1
  Falloff falloff = Falloff::smooth;
  bool invert = false;  // also while Ctrl is held at the start of a stroke
  bool front_faces_only = true;
  std::array<bool, 3> symmetry = {true, false, false};  // mirror across x = 0, y = 0, z = 0
  bool pressure_radius = false;
  bool pressure_strength = true;
  PaintChannel paint_channel = PaintChannel::albedo;
  glm::vec3 colour{0.85f, 0.18f, 0.12f};  // sRGB, as stored in the albedo channel
  float roughness = 0.15f;
  float metallic = 1.f;
};

/** Weight at normalised distance d in [0, 1] from the dab's centre (1 at the centre, 0 at
 *  the rim except for the constant preset). */
float falloff_weight(Falloff falloff, float d);
