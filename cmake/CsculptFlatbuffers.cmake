# csculpt_flatbuffers(TARGET schema.fbs...): generates <name>_generated.h for each schema with
# Debian's flatc at build time and puts them on TARGET's private include path, with the
# FlatBuffers headers. The runtime parts we use (builder, verifier) are header-only, so nothing
# is linked: a static library built with it can go into a shared one without a non-PIC archive.
find_package(FlatBuffers REQUIRED)
get_target_property(CSCULPT_FLATBUFFERS_INCLUDE flatbuffers::flatbuffers INTERFACE_INCLUDE_DIRECTORIES)

function(csculpt_flatbuffers target)
  set(out ${CMAKE_CURRENT_BINARY_DIR}/generated)
  set(headers)
  foreach(schema ${ARGN})
    get_filename_component(name ${schema} NAME_WE)
    set(header ${out}/${name}_generated.h)
    add_custom_command(
      OUTPUT ${header}
      COMMAND flatbuffers::flatc --cpp --scoped-enums -o ${out} ${schema}
      DEPENDS ${schema} flatbuffers::flatc
      COMMENT "flatc ${name}.fbs"
      VERBATIM)
    list(APPEND headers ${header})
  endforeach()
  target_sources(${target} PRIVATE ${headers})
  target_include_directories(${target} PRIVATE ${out})
  target_include_directories(${target} SYSTEM PRIVATE ${CSCULPT_FLATBUFFERS_INCLUDE})
  add_custom_target(${target}_schemas DEPENDS ${headers})
endfunction()
