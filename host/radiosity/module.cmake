# The radiosity update's AVX kernels (update_avx.c) are built with -mavx;
# the solver calls them only where the CPU has AVX (a run-time check).
# Elsewhere update_avx.c builds as baseline code that is never called.
if(CMAKE_SYSTEM_PROCESSOR MATCHES "^(x86_64|AMD64|amd64|i[3-6]86)$")
  set_source_files_properties(${CMAKE_CURRENT_LIST_DIR}/update_avx.c PROPERTIES COMPILE_OPTIONS "-mavx")
  add_compile_definitions(TB_RAD_AVX)
endif()
