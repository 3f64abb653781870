# Build helpers: the warning and sanitizer flags every target shares, and the library pattern.
add_library(selfsense_build_flags INTERFACE)
add_library(selfsense::build_flags ALIAS selfsense_build_flags)
target_compile_options(selfsense_build_flags INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wsign-conversion -Wold-style-cast
  -Wnon-virtual-dtor -Woverloaded-virtual -Wdouble-promotion
  $<$<BOOL:${SELFSENSE_WERROR}>:-Werror>)
if(SELFSENSE_SANITIZE)
  target_compile_options(selfsense_build_flags INTERFACE
    -fsanitize=${SELFSENSE_SANITIZE} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  target_link_options(selfsense_build_flags INTERFACE -fsanitize=${SELFSENSE_SANITIZE})
  if(SELFSENSE_SANITIZE MATCHES "thread")
    # GCC warns that TSan does not model std::atomic_thread_fence; the sequence lock's data are
    # atomics themselves (runtime/latest_value.hpp), so the warning is not a finding.
    target_compile_options(selfsense_build_flags INTERFACE -Wno-tsan)
  endif()
endif()

# libFuzzer (tests/fuzz, docs/reliability.md): every library is built with the fuzzer's coverage
# instrumentation (-fsanitize=fuzzer-no-link), the fuzz targets link libFuzzer's main. The
# instrumentation's hooks come from the sanitizer runtimes, hence a sanitizer is required.
if(SELFSENSE_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "SELFSENSE_FUZZ=ON needs clang (libFuzzer); configure with CXX=clang++")
  endif()
  if(NOT SELFSENSE_SANITIZE)
    message(FATAL_ERROR "SELFSENSE_FUZZ=ON needs SELFSENSE_SANITIZE (e.g. address,undefined)")
  endif()
  target_compile_options(selfsense_build_flags INTERFACE -fsanitize=fuzzer-no-link)
  target_link_options(selfsense_build_flags INTERFACE -fsanitize=fuzzer-no-link)
endif()

# Registers a target for installation in the selfsense export set.
function(selfsense_export target)
  set_property(GLOBAL APPEND PROPERTY SELFSENSE_EXPORTED_TARGETS ${target})
endfunction()

# selfsense_library(<target> EXPORT_NAME <name> SOURCES ... [PUBLIC deps...] [PRIVATE deps...])
# A library of the project: alias selfsense::<name>, the public include folder, the shared
# flags, and a place in the export set.
function(selfsense_library target)
  cmake_parse_arguments(ARG "" "EXPORT_NAME" "SOURCES;PUBLIC;PRIVATE" ${ARGN})
  add_library(${target} ${ARG_SOURCES})
  add_library(selfsense::${ARG_EXPORT_NAME} ALIAS ${target})
  target_include_directories(${target} PUBLIC
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/include> $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(${target} PUBLIC ${ARG_PUBLIC} PRIVATE ${ARG_PRIVATE} selfsense_build_flags)
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${ARG_EXPORT_NAME})
  # Under the sanitizers the product's code is built at -O1 (clang's advice for ASan): unoptimised,
  # the daemon's 10 kHz cycle with a Preisach-class model took 131 us at p99 and the process
  # tests could not arm. The tests' own code stays at the build type's level.
  if(SELFSENSE_SANITIZE)
    target_compile_options(${target} PRIVATE -O1)
  endif()
  selfsense_export(${target})
endfunction()
