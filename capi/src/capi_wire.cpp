// The C ABI of the wire format: a diff encoded into bytes (csc_bytes), peeked and decoded.
#include <cmath>
#include <cstring>
#include <string>

#include "capi_internal.h"
#include "csculpt/wire.h"

using namespace csculpt::capi;
using csculpt::InvalidInput;

namespace {

std::span<const std::uint8_t> byte_span(const void* data, std::size_t size) {
  if (data == nullptr && size > 0) bad_argument("data is NULL");
  return {static_cast<const std::uint8_t*>(data), size};
}

csc_message_info message_info(const csculpt::DiffHeader& h, const char* author) {
  csc_message_info v = CSC_MESSAGE_INFO_INIT;
  v.protocol = h.protocol;
  v.base_version = h.base_version;
  v.sequence = h.sequence;
  v.vertex_count = h.vertex_count;
  v.author = author;
  return v;
}

}  // namespace

extern "C" {

CSC_API csc_status csc_diff_encode(csc_bytes** out, const csc_diff* diff, const csc_mesh* base,
                                   const csc_encode_options* options) {
  return guarded("csc_diff_encode", [&] {
    require_pointer(out, "out");
    const csculpt::Diff& d = handle(diff, Tag::diff, "diff").diff;
    const csculpt::Mesh& b = handle(base, Tag::mesh, "base").mesh;
    csc_encode_options o = CSC_ENCODE_OPTIONS_INIT;
    if (options != nullptr) o = read_in(options, o, "options");
    if (!(o.position_tolerance >= 0) || !(o.channel_tolerance >= 0) || !(o.position_scale >= 0) ||
        !std::isfinite(o.position_tolerance) || !std::isfinite(o.channel_tolerance) ||
        !std::isfinite(o.position_scale))
      bad_argument("options: tolerances and scale must be finite and >= 0");
    csculpt::DiffHeader header;
    header.base_version = o.base_version;
    header.sequence = o.sequence;
    if (o.author != nullptr) {
      const std::size_t len = strnlen(o.author, csculpt::max_author_bytes + 1);
      if (len > csculpt::max_author_bytes)
        bad_argument("options->author is longer than " + std::to_string(csculpt::max_author_bytes) +
                     " bytes");
      header.author = std::string_view(o.author, len);
    }
    csculpt::EncodeOptions eo;
    eo.position_tolerance = o.position_tolerance;
    eo.position_scale = o.position_scale;
    eo.channel_tolerance = o.channel_tolerance;
    auto h = std::make_unique<csc_bytes>();
    h->data = csculpt::encode_diff(d, b, header, eo);
    *out = h.release();
  });
}

CSC_API const uint8_t* csc_bytes_data(const csc_bytes* bytes) {
  return is(bytes, Tag::bytes) ? bytes->data.data() : nullptr;
}
CSC_API size_t csc_bytes_size(const csc_bytes* bytes) {
  return is(bytes, Tag::bytes) ? bytes->data.size() : 0;
}
CSC_API void csc_bytes_destroy(csc_bytes* bytes) {
  destroy(bytes, Tag::bytes);
}

CSC_API csc_status csc_diff_peek(const void* data, size_t size, csc_message_info* info) {
  return guarded("csc_diff_peek", [&] {
    require_pointer(info, "info");
    require_struct_size(info->struct_size, first_published_size<csc_message_info>, "info");
    const csculpt::DiffHeader h = csculpt::peek_diff_header(byte_span(data, size));
    // FlatBuffers strings are NUL-terminated in the buffer (checked by the verifier), and an
    // author with an inner NUL is refused, so the view is a C string; "" when absent.
    write_out(info, message_info(h, h.author.data() ? h.author.data() : ""), "info");
  });
}

CSC_API csc_status csc_diff_decode(csc_diff** out, const csc_mesh* base, uint64_t base_version,
                                   const void* data, size_t size, csc_message_info* info) {
  return guarded("csc_diff_decode", [&] {
    require_pointer(out, "out");
    const csculpt::Mesh& b = handle(base, Tag::mesh, "base").mesh;
    if (info != nullptr)
      require_struct_size(info->struct_size, first_published_size<csc_message_info>, "info");
    const auto bytes = byte_span(data, size);
    const csculpt::DiffHeader peeked = csculpt::peek_diff_header(bytes);
    if (peeked.base_version != base_version)
      throw BaseVersionError{"the message is based on version " +
                             std::to_string(peeked.base_version) + ", not " +
                             std::to_string(base_version)};
    csculpt::DiffHeader h;
    auto d = new_diff(csculpt::decode_diff(bytes, b, &h));
    d->author.assign(h.author);
    if (info != nullptr) write_out(info, message_info(h, d->author.c_str()), "info");
    *out = d.release();
  });
}

}  // extern "C"
