# yaml-cpp for a Debian cross build (cmake/toolchains/debian-cross.cmake): the target's shared
# library from libyaml-cpp0.7:ARCH (multiarch) and the headers of libyaml-cpp-dev, which are the
# same for every architecture. Debian 12's libyaml-cpp-dev cannot be installed for a second
# architecture beside the build machine's (it is not Multi-Arch: same). /usr/include is on the
# cross compiler's search path (Debian's multiarch layout): no include directory to add.
set(_yaml_cpp_lib /usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}/libyaml-cpp.so.0.7)
if(NOT EXISTS ${_yaml_cpp_lib} OR NOT EXISTS /usr/include/yaml-cpp/yaml.h)
  set(yaml-cpp_FOUND FALSE)
  set(yaml-cpp_NOT_FOUND_MESSAGE
    "needs ${_yaml_cpp_lib} (libyaml-cpp0.7:ARCH) and /usr/include/yaml-cpp (libyaml-cpp-dev)")
  return()
endif()
if(NOT TARGET yaml-cpp)
  add_library(yaml-cpp SHARED IMPORTED)
  set_target_properties(yaml-cpp PROPERTIES
    IMPORTED_LOCATION ${_yaml_cpp_lib}
    IMPORTED_SONAME libyaml-cpp.so.0.7)
endif()
set(YAML_CPP_INCLUDE_DIR /usr/include)
set(YAML_CPP_LIBRARIES yaml-cpp)
set(yaml-cpp_VERSION 0.7.0)
set(yaml-cpp_FOUND TRUE)
