// A triangle mesh with per-vertex attribute channels, stored as flat arrays.
//
// The merge works on plain arrays (one array per attribute: positions, each channel) so that
// a host's own buffers map onto it without conversion and the hot loops stream memory.
// OpenMesh interop lives in openmesh_interop.h.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace csculpt {

struct Vec3f {
  float x = 0, y = 0, z = 0;
  friend bool operator==(const Vec3f&, const Vec3f&) = default;
};

using Triangle = std::array<std::uint32_t, 3>;

/// How a channel's stored values map to the linear space in which edits are merged
/// (paper §3.2: material parameters are merged after projection on a linear space).
enum class Linearisation : std::uint32_t {
  identity = 0,  ///< stored values are already linear (metallic, masks)
  square = 1,    ///< linear = v^2, stored = sqrt(linear) (roughness -> alpha)
  srgb = 2,      ///< stored sRGB-encoded colour in [0,1], linear = sRGB EOTF(v)
};

std::string_view to_string(Linearisation lin);
/// Parses "identity" / "linear", "square", "srgb"; throws InvalidInput otherwise.
Linearisation linearisation_from_string(std::string_view name);

/// Both maps are extended to all reals as odd functions (f(-v) = -f(v)), so merged values that
/// step slightly outside [0,1] stay finite and the two remain mutual inverses.
float to_linear(Linearisation lin, float stored);
float from_linear(Linearisation lin, float linear);

/// The linearisation a channel gets from its name when a file does not say: albedo -> srgb,
/// roughness -> square, anything else identity.
Linearisation default_linearisation(std::string_view channel_name);

/// A named per-vertex float attribute with `width` components (1..4), e.g. albedo (3).
struct ChannelDesc {
  std::string name;
  std::uint32_t width = 1;
  Linearisation linearisation = Linearisation::identity;
  /// Valid range of stored values; merged values are clamped into it (two independent
  /// edits can add up beyond what either painted).
  float min_value = -std::numeric_limits<float>::infinity();
  float max_value = std::numeric_limits<float>::infinity();
  friend bool operator==(const ChannelDesc&, const ChannelDesc&) = default;
};

/// The description a channel called `name` gets when a file does not say more: the
/// material channels' linearisation and [0, 1] range, identity and unbounded otherwise.
ChannelDesc default_channel(std::string_view name, std::uint32_t width);

struct Channel {
  ChannelDesc desc;
  std::vector<float> values;  ///< vertex_count * desc.width, vertex-major
};

/// The built-in material channel set (paper §3.2): albedo (RGB, sRGB), metallic (linear),
/// roughness (squared).
std::vector<ChannelDesc> material_channels();

/// The built-in material channels' default: a grey rough dielectric (what the C ABI's
/// csc_mesh_add_material_channels and the built-in meshes fill them with).
inline constexpr float default_albedo = 0.5f;  ///< each of R, G and B, sRGB-encoded
inline constexpr float default_metallic = 0.f;
inline constexpr float default_roughness = 0.7f;
/// `desc.width` values of the default above for the material channel `desc` (albedo, metallic,
/// roughness, by name); 0 for any other channel.
std::vector<float> default_material_fill(const ChannelDesc& desc);

struct Mesh {
  std::vector<Vec3f> positions;
  std::vector<Triangle> triangles;
  std::vector<Channel> channels;

  std::size_t vertex_count() const { return positions.size(); }
  std::size_t face_count() const { return triangles.size(); }

  /// Index of the channel called `name`, or -1.
  int find_channel(std::string_view name) const;
  /// Adds a channel filled with `fill` (width values) if it does not exist; returns its index.
  int add_channel(const ChannelDesc& desc, std::span<const float> fill = {});
};

/// Whether a mesh must have faces. A mesh that is merged, captured or written must; the
/// positions a merge is compared with (an ideal result, stored without its base's faces) need
/// not.
enum class Faces { required, optional };

/// Throws InvalidInput (prefixed with `what`, e.g. a file name) when the mesh cannot be
/// merged: no vertices, no faces (unless `faces` is optional), a triangle index out of range
/// or repeated within a face, a NaN/Inf position or channel value, a channel of the wrong
/// size or width.
void validate(const Mesh& mesh, std::string_view what, Faces faces = Faces::required);

/// Throws InvalidInput unless `edited` has the same vertex count, triangles and channel
/// layout as `base`.
void check_same_connectivity(const Mesh& base, const Mesh& edited, std::string_view what);

/// Axis-aligned bounding box diagonal length of the positions (0 for an empty mesh).
float bbox_diagonal(std::span<const Vec3f> positions);

}  // namespace csculpt
