# The wide BVH's AVX traversal (bvh_wide_avx.c) is the only code built with
# -mavx; the library calls it only where the CPU has AVX (a run-time check),
# so the build stays x86-64 baseline everywhere else. Other architectures
# build the SSE2 (or scalar) traversal alone.
if(CMAKE_SYSTEM_PROCESSOR MATCHES "^(x86_64|AMD64|amd64|i[3-6]86)$")
  set_source_files_properties(${CMAKE_CURRENT_LIST_DIR}/bvh_wide_avx.c PROPERTIES COMPILE_OPTIONS "-mavx")
  add_compile_definitions(TB_BVH_AVX)
endif()
