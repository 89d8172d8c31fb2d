# Cross build for 64-bit ARM Linux (aarch64) with Debian's cross toolchain, tests run
# under user-mode emulation:
#   scripts/deps arm64     # crossbuild-essential-arm64, qemu-user, the :arm64 -dev packages
#   cmake -S . -B build-arm64 -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/aarch64-linux-gnu.cmake
#   cmake --build build-arm64 -j && (cd build-arm64 && ctest)   # or scripts/test_arm64
#
# Libraries: Debian multiarch. The arm64 packages (libgtest-dev:arm64, libpng-dev:arm64,
# libjpeg62-turbo-dev:arm64, libbenchmark-dev:arm64) install into /usr/lib/aarch64-linux-gnu
# beside the host's /usr/lib/x86_64-linux-gnu, with the headers shared in /usr/include;
# CMAKE_LIBRARY_ARCHITECTURE makes every find_* look in the aarch64 folders. The search
# is not re-rooted into /usr/aarch64-linux-gnu alone: header-only packages of the host
# (Eigen's CMake package in /usr/share/eigen3) must still be found there, and programs
# (python3 for the PyTorch references) are the host's. The C/C++ runtime and libgomp
# (OpenMP) come with the cross compiler from /usr/aarch64-linux-gnu.
#
# Tests: CMAKE_CROSSCOMPILING_EMULATOR runs every test whose command is one of our
# targets (and gtest_discover_tests' listing) through qemu-aarch64; commands that are not
# targets (/usr/bin/python3 for the reference scripts) run directly on the host.
# A board with a native compiler needs none of this: configure there without a toolchain.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)

set(ROADNN_CROSS_TRIPLE aarch64-linux-gnu)
set(CMAKE_C_COMPILER ${ROADNN_CROSS_TRIPLE}-gcc)
set(CMAKE_CXX_COMPILER ${ROADNN_CROSS_TRIPLE}-g++)
set(CMAKE_LIBRARY_ARCHITECTURE ${ROADNN_CROSS_TRIPLE})

set(CMAKE_FIND_ROOT_PATH /usr/${ROADNN_CROSS_TRIPLE})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)
# pkg-config (used by no find_package of ours today) would report the host's .pc files.
set(ENV{PKG_CONFIG_LIBDIR} /usr/lib/${ROADNN_CROSS_TRIPLE}/pkgconfig:/usr/share/pkgconfig)

# -L: where qemu finds the aarch64 dynamic loader (the cross toolchain's, from
# libc6-arm64-cross). The loader and libc must come from the same glibc build: the host's
# ld.so.cache also lists the multiarch libc6:arm64 (pulled in by the :arm64 -dev packages
# and often a newer Debian revision), and that libc under the cross loader corrupts the
# loader's thread-stack list: the first pthread_create (OpenMP's team) spins forever.
# LD_LIBRARY_PATH, searched before the cache, takes libc, libstdc++ and libgomp from the
# cross toolchain and the multiarch libraries (libpng, libjpeg, libz) from
# /usr/lib/aarch64-linux-gnu.
find_program(ROADNN_QEMU_AARCH64 qemu-aarch64)
if(ROADNN_QEMU_AARCH64)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${ROADNN_QEMU_AARCH64} -L /usr/${ROADNN_CROSS_TRIPLE}
      -E LD_LIBRARY_PATH=/usr/${ROADNN_CROSS_TRIPLE}/lib:/usr/lib/${ROADNN_CROSS_TRIPLE})
endif()
