# Shared part of the Debian cross toolchains (aarch64-linux-gnu.cmake, arm-linux-gnueabihf.cmake):
# Debian's cross compilers (crossbuild-essential-ARCH) and the target's libraries installed as
# multiarch packages (dpkg --add-architecture ARCH; libmodbus-dev:ARCH, ...) under
# /usr/lib/TRIPLET, no sysroot. The including file sets SELFSENSE_CROSS_TRIPLET,
# SELFSENSE_CROSS_DEB_ARCH, SELFSENSE_CROSS_PROCESSOR and SELFSENSE_CROSS_QEMU.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR ${SELFSENSE_CROSS_PROCESSOR})
set(CMAKE_C_COMPILER ${SELFSENSE_CROSS_TRIPLET}-gcc)
set(CMAKE_CXX_COMPILER ${SELFSENSE_CROSS_TRIPLET}-g++)
# find_library and find_package search /usr/lib/TRIPLET (multiarch), never the build machine's
# /usr/lib/x86_64-linux-gnu; headers in /usr/include are shared by every architecture.
set(CMAKE_LIBRARY_ARCHITECTURE ${SELFSENSE_CROSS_TRIPLET})
set(CMAKE_IGNORE_PREFIX_PATH /usr/local)
foreach(_host_triplet x86_64-linux-gnu i386-linux-gnu)
  list(APPEND CMAKE_IGNORE_PATH /usr/lib/${_host_triplet} /lib/${_host_triplet}
    /usr/lib/${_host_triplet}/cmake)
endforeach()
# pkg-config reads the target's .pc files only.
set(ENV{PKG_CONFIG_LIBDIR} /usr/lib/${SELFSENSE_CROSS_TRIPLET}/pkgconfig:/usr/share/pkgconfig)
set(ENV{PKG_CONFIG_PATH} "")
# Debian 12's libyaml-cpp-dev is not Multi-Arch: same (it conflicts with the build machine's):
# the target's libyaml-cpp0.7 and the architecture-independent headers of the build machine's
# libyaml-cpp-dev, joined by cmake/toolchains/yaml-cpp/yaml-cpp-config.cmake.
set(yaml-cpp_DIR ${CMAKE_CURRENT_LIST_DIR}/yaml-cpp CACHE PATH "yaml-cpp for the target (cross build)")
# The target's programs (tests, gtest_discover_tests) run under qemu-user on the target's own
# Debian runtime, as on a board: the loader and libc of libc6:ARCH (/lib/ld-linux-*.so, the
# path in the programs), the libraries of the multiarch packages. Not the cross toolchain's
# libc in /usr/TRIPLET (-L): its loader with libc6:ARCH's libc.so.6, which a library pulls in,
# hangs the first pthread_create (two builds of glibc 2.36 disagreeing on the loader's data).
set(CMAKE_CROSSCOMPILING_EMULATOR ${SELFSENSE_CROSS_QEMU}
  -E LD_LIBRARY_PATH=/lib/${SELFSENSE_CROSS_TRIPLET}:/usr/lib/${SELFSENSE_CROSS_TRIPLET})
# The Debian architecture of the packages (cmake/SelfsensePackage.cmake).
set(SELFSENSE_DEB_ARCH ${SELFSENSE_CROSS_DEB_ARCH})
