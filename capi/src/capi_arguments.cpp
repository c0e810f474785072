// The checks and conversions of a caller's arguments that several handle types share.
#include <string>

#include "capi_internal.h"

namespace csculpt::capi {

void require_struct_size(std::uint32_t declared, std::size_t minimum, const char* name) {
  if (declared < minimum)
    bad_argument(std::string(name) + "->struct_size is " + std::to_string(declared) +
                 ", at least " + std::to_string(minimum) +
                 " expected (initialise it with the _INIT macro)");
}

Linearisation to_linearisation(csc_linearisation lin) {
  switch (lin) {
    case CSC_LINEARISATION_IDENTITY:
      return Linearisation::identity;
    case CSC_LINEARISATION_SQUARE:
      return Linearisation::square;
    case CSC_LINEARISATION_SRGB:
      return Linearisation::srgb;
    default:
      bad_argument("unknown linearisation " + std::to_string(static_cast<long long>(lin)));
  }
}

csc_linearisation from_linearisation(Linearisation lin) {
  return static_cast<csc_linearisation>(static_cast<std::uint32_t>(lin));
}

std::span<const float> floats(const std::vector<Vec3f>& v) {
  static_assert(sizeof(Vec3f) == 3 * sizeof(float));
  return {reinterpret_cast<const float*>(v.data()), v.size() * 3};
}

/// The host's arrays, checked against the base mesh's layout.
csc_vertex_arrays host_arrays(const csc_vertex_arrays* in, const Mesh& base, const char* name) {
  const csc_vertex_arrays defaults = CSC_VERTEX_ARRAYS_INIT;
  const csc_vertex_arrays arrays = read_in(in, defaults, name);
  const csc_vertex_arrays* a = &arrays;
  // Counts that do not match the base are bad data (the header's contract), not a bad call.
  if (a->vertex_count != base.vertex_count())
    throw InvalidInput(std::string(name) + " has " + std::to_string(a->vertex_count) +
                       " vertices but the base mesh has " + std::to_string(base.vertex_count()));
  if (a->positions == nullptr) bad_argument(std::string(name) + "->positions is NULL");
  if (a->channel_count != base.channels.size())
    throw InvalidInput(std::string(name) + " has " + std::to_string(a->channel_count) +
                       " channels but the base mesh has " + std::to_string(base.channels.size()));
  if (a->channel_count > 0 && a->channels == nullptr)
    bad_argument(std::string(name) + "->channels is NULL");
  return arrays;
}

std::unique_ptr<csc_diff> new_diff(Diff d) {
  auto h = std::make_unique<csc_diff>();
  h->diff = std::move(d);
  return h;
}

}  // namespace csculpt::capi
