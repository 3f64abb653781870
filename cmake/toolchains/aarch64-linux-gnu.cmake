# Cross build for Debian arm64 (Raspberry Pi CM4/CM5, i.MX 8, Zynq UltraScale+):
#   cmake -S . -B build-arm64 -G Ninja --toolchain cmake/toolchains/aarch64-linux-gnu.cmake
# Needs crossbuild-essential-arm64 and the arm64 libraries (scripts/setup.sh package installs them).
set(SELFSENSE_CROSS_TRIPLET aarch64-linux-gnu)
set(SELFSENSE_CROSS_DEB_ARCH arm64)
set(SELFSENSE_CROSS_PROCESSOR aarch64)
set(SELFSENSE_CROSS_QEMU qemu-aarch64)
include(${CMAKE_CURRENT_LIST_DIR}/debian-cross.cmake)
