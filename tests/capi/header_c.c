/* csculpt.h alone, first, as strict C99: it must be self-contained and warning-free.
   header_cpp.cpp compiles the same checks as C++11. */
#include "csculpt.h"

/* The _INIT macros must be valid initialisers, every one of them. */
int csculpt_header_c_check(void);
int csculpt_header_c_check(void) {
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
  csc_session_options session = CSC_SESSION_OPTIONS_INIT;
  csc_session_event event = CSC_SESSION_EVENT_INIT;
  csc_session_stats session_stats = CSC_SESSION_STATS_INIT;
  /* Enums are 32-bit (the header's promise; a negative array size fails the build). */
  typedef char enums_are_32_bit[sizeof(csc_status) == 4 && sizeof(csc_linearisation) == 4 &&
                                        sizeof(csc_merge_method) == 4 && sizeof(csc_event_kind) == 4
                                    ? 1
                                    : -1];
  enums_are_32_bit unused;
  (void)unused;
  /* (a comparison, not a cast: the C++ build forbids old-style casts) */
  return desc.struct_size + view.struct_size + hierarchy.struct_size + stats.struct_size +
             arrays.struct_size + info.struct_size + message.struct_size + encode.struct_size +
             merge.struct_size + timings.struct_size + session.struct_size + event.struct_size +
             session_stats.struct_size >
         0u;
}
