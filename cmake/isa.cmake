# Run-time ISA dispatch (nn/isa.h, nn/kernel_table.h). The kernels of each architecture
# live in nn/arch/<arch>/; only the folder of the target architecture is compiled:
#   x86-64 (ROADNN_ARCH x86): a file whose name ends in _avx2.cpp, _avx512.cpp or
#     _avx512bf16.cpp (AVX-512 plus AVX512_BF16) is compiled with that instruction set
#     enabled; every other file is baseline x86-64.
#   aarch64 (ROADNN_ARCH arm): Advanced SIMD is baseline, so *_neon.cpp needs no flag.
#   anything else (ROADNN_ARCH generic): the scalar kernels only.
# ISA files must only export plain functions with the ISA in their name and keep all
# helpers in an anonymous namespace: an inline function or template instantiated there
# could otherwise be picked by the linker for baseline callers (and fault on older CPUs).
if(CMAKE_SYSTEM_PROCESSOR MATCHES "^(x86_64|AMD64|amd64)$")
  set(ROADNN_ARCH x86)
elseif(CMAKE_SYSTEM_PROCESSOR MATCHES "^(aarch64|arm64|ARM64)$")
  set(ROADNN_ARCH arm)
else()
  set(ROADNN_ARCH generic)
endif()
message(STATUS "roadnn: kernels for ${ROADNN_ARCH} (${CMAKE_SYSTEM_PROCESSOR})")

set(ROADNN_AVX2_FLAGS -mavx2 -mfma -mf16c)
set(ROADNN_AVX512_FLAGS -mavx512f -mavx512bw -mavx512dq -mavx512vl -mavx2 -mfma -mf16c)
set(ROADNN_AVX512BF16_FLAGS ${ROADNN_AVX512_FLAGS} -mavx512bf16)

function(roadnn_isa_flags)
  if(NOT ROADNN_ARCH STREQUAL "x86")
    return()
  endif()
  foreach(src IN LISTS ARGN)
    if(src MATCHES "_avx512bf16\\.cpp$")
      set_source_files_properties(${src} PROPERTIES COMPILE_OPTIONS "${ROADNN_AVX512BF16_FLAGS}")
    elseif(src MATCHES "_avx512\\.cpp$")
      set_source_files_properties(${src} PROPERTIES COMPILE_OPTIONS "${ROADNN_AVX512_FLAGS}")
    elseif(src MATCHES "_avx2\\.cpp$")
      set_source_files_properties(${src} PROPERTIES COMPILE_OPTIONS "${ROADNN_AVX2_FLAGS}")
    endif()
  endforeach()
endfunction()

# Links the thread library when the engine has worker threads (ROADNN_WITH_THREADS); the
# runtime code tests ROADNN_THREADS so that a single-threaded build is explicit.
function(roadnn_link_threads target)
  if(ROADNN_WITH_THREADS)
    target_link_libraries(${target} PUBLIC Threads::Threads)
    target_compile_definitions(${target} PUBLIC ROADNN_THREADS=1)
  endif()
endfunction()
