# Warnings as an INTERFACE target: every project target links it, third-party
# headers (Eigen, HDF5, nlohmann-json) are included as SYSTEM and stay quiet.
add_library(gabion_warnings INTERFACE)
target_compile_options(gabion_warnings INTERFACE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor)
if(GABION_WERROR)
  target_compile_options(gabion_warnings INTERFACE -Werror)
endif()

add_library(gabion_options INTERFACE)
target_include_directories(gabion_options INTERFACE ${PROJECT_SOURCE_DIR} ${PROJECT_BINARY_DIR}/generated)
if(GABION_NATIVE)
  include(CheckCXXCompilerFlag)
  check_cxx_compiler_flag(-march=native GABION_HAS_MARCH_NATIVE)
  if(GABION_HAS_MARCH_NATIVE)
    target_compile_options(gabion_options INTERFACE -march=native)
    # (tests that pin bit patterns need to know: the compiler fuses
    # multiply-adds where the CPU has them, so native bits depend on the CPU)
    target_compile_definitions(gabion_options INTERFACE GABION_NATIVE_BUILD=1)
    # GCC 12 reports Eigen's AVX-512 intrinsics (avx512fintrin.h, _mm512_undefined)
    # as "used uninitialized" once inlined into our code: a false positive of
    # that header. The portable CI build (GABION_NATIVE=OFF, -Werror) keeps
    # both warnings on for our code.
    target_compile_options(gabion_options INTERFACE -Wno-uninitialized -Wno-maybe-uninitialized)
  endif()
endif()
