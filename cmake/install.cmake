# Install rules of the library roadnn (included when ROADNN_INSTALL is ON):
#   include/roadnn/*.h, *.hpp           the public headers, nothing else
#   lib/libroadnn.a or libroadnn.so*    the library (the internal ones are inside it)
#   lib/cmake/roadnn/                   roadnnConfig.cmake, roadnnConfigVersion.cmake,
#                                       roadnnTargets*.cmake (imported target roadnn::roadnn)
#   lib/pkgconfig/roadnn.pc
# Nothing installed needs Eigen, libpng or libjpeg.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(ROADNN_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/roadnn)
get_target_property(roadnn_type roadnn TYPE)
if(roadnn_type STREQUAL "SHARED_LIBRARY")
  set(ROADNN_SHARED ON)
else()
  set(ROADNN_SHARED OFF)
endif()

install(TARGETS roadnn EXPORT roadnnTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
        FILE_SET HEADERS DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT roadnnTargets NAMESPACE roadnn:: DESTINATION ${ROADNN_CMAKE_DIR})

# Version compatibility: from 1.0 on, any release of the same major version satisfies
# find_package(roadnn X.Y) if it is at least X.Y (SameMajorVersion). While the major
# version is 0 every minor release may break the API, so the minor version must match
# too (SameMinorVersion: 0.2.x satisfies 0.2, 0.3 does not), as in the SONAME.
if(PROJECT_VERSION_MAJOR EQUAL 0)
  set(ROADNN_COMPATIBILITY SameMinorVersion)
else()
  set(ROADNN_COMPATIBILITY SameMajorVersion)
endif()
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/roadnnConfig.cmake.in
  ${PROJECT_BINARY_DIR}/roadnnConfig.cmake INSTALL_DESTINATION ${ROADNN_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/roadnnConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY ${ROADNN_COMPATIBILITY})
install(FILES ${PROJECT_BINARY_DIR}/roadnnConfig.cmake ${PROJECT_BINARY_DIR}/roadnnConfigVersion.cmake
        DESTINATION ${ROADNN_CMAKE_DIR})

# roadnn.pc, relocatable: its paths are relative to where it is installed (${pcfiledir}),
# so `cmake --install --prefix P` gives a working P/lib/pkgconfig/roadnn.pc.
# Libs.private (pkg-config --static): what the C++ compiler links beyond the C compiler
# (libstdc++, libm for GCC) and the thread flag.
# (An absolute CMAKE_INSTALL_LIBDIR / INCLUDEDIR is written as given.)
if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}")
  set(ROADNN_PC_PREFIX ${CMAKE_INSTALL_PREFIX})
else()
  file(RELATIVE_PATH rel /prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig /prefix)
  string(REGEX REPLACE "/$" "" rel "${rel}")
  set(ROADNN_PC_PREFIX "\${pcfiledir}/${rel}")
endif()
foreach(dir LIBDIR INCLUDEDIR)
  if(IS_ABSOLUTE "${CMAKE_INSTALL_${dir}}")
    set(ROADNN_PC_${dir} ${CMAKE_INSTALL_${dir}})
  else()
    set(ROADNN_PC_${dir} "\${prefix}/${CMAKE_INSTALL_${dir}}")
  endif()
endforeach()
set(ROADNN_PC_LIBS_PRIVATE "")
foreach(lib IN LISTS CMAKE_CXX_IMPLICIT_LINK_LIBRARIES)
  if(NOT lib IN_LIST CMAKE_C_IMPLICIT_LINK_LIBRARIES)
    list(APPEND ROADNN_PC_LIBS_PRIVATE -l${lib})
  endif()
endforeach()
if(ROADNN_WITH_THREADS)
  list(APPEND ROADNN_PC_LIBS_PRIVATE -pthread)
endif()
list(JOIN ROADNN_PC_LIBS_PRIVATE " " ROADNN_PC_LIBS_PRIVATE)
configure_file(${CMAKE_CURRENT_LIST_DIR}/roadnn.pc.in ${PROJECT_BINARY_DIR}/roadnn.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/roadnn.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
