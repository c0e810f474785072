// csculpt.h alone, first, as C++11 with strict warnings: self-contained and extern "C".
#include "csculpt.h"

namespace {
static_assert(sizeof(csc_status) == 4 && sizeof(csc_linearisation) == 4 &&
                  sizeof(csc_merge_method) == 4,
              "the header promises 32-bit enums");
}  // namespace

// The _INIT macros must be valid C++ initialisers, and the functions must have C linkage
// (taking their address as a pointer to an extern "C" function type).
extern "C" typedef csc_status csc_peek_fn(const void*, size_t, csc_message_info*);
int csculpt_header_cpp_check();
int csculpt_header_cpp_check() {
  csc_mesh_desc desc = CSC_MESH_DESC_INIT;
  csc_channel_view view = CSC_CHANNEL_VIEW_INIT;
  csc_hierarchy_options hierarchy = CSC_HIERARCHY_OPTIONS_INIT;
  csc_hierarchy_stats stats = CSC_HIERARCHY_STATS_INIT;
  csc_vertex_arrays arrays = CSC_VERTEX_ARRAYS_INIT;
  csc_diff_info info = CSC_DIFF_INFO_INIT;
  csc_message_info message = CSC_MESSAGE_INFO_INIT;
  csc_encode_options encode = CSC_ENCODE_OPTIONS_INIT;
  csc_merge_options merge = CSC_MERGE_OPTIONS_INIT;
  csc_merge_timings timings = CSC_MERGE_TIMINGS_INIT;
  csc_peek_fn* peek = &csc_diff_peek;
  return static_cast<int>(desc.struct_size + view.struct_size + hierarchy.struct_size +
                          stats.struct_size + arrays.struct_size + info.struct_size +
                          message.struct_size + encode.struct_size + merge.struct_size +
                          timings.struct_size) +
         (peek != nullptr ? 1 : 0);
}
