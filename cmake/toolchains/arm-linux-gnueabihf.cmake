# Cross build for Debian armhf (32-bit ARMv7 with hardware float: BeagleBone, Zynq-7000):
#   cmake -S . -B build-armhf -G Ninja --toolchain cmake/toolchains/arm-linux-gnueabihf.cmake
# Needs crossbuild-essential-armhf and the armhf libraries (scripts/setup.sh package installs them).
set(SELFSENSE_CROSS_TRIPLET arm-linux-gnueabihf)
set(SELFSENSE_CROSS_DEB_ARCH armhf)
set(SELFSENSE_CROSS_PROCESSOR armv7l)
set(SELFSENSE_CROSS_QEMU qemu-arm)
include(${CMAKE_CURRENT_LIST_DIR}/debian-cross.cmake)
