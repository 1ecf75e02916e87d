# Debian packages of the install components, made by cpack from one build (docs/packaging.md):
#   hapticd          (server)  the server, its configuration as a conffile, the systemd unit,
#                              sysusers.d and tmpfiles.d files, the viewer's page, the drivers and
#                              haptic-driver-kit
#   hapticd-tools    (tools)   hapticctl, touch_wall and multi_user: clients, no server
#   libhaptic-c1     (c)       libhaptic_c.so.1, the C API's runtime (C, C#, MATLAB, ...)
#   libhapticd-dev   (dev)     headers, the static SDK, the CMake package, libhaptic_c.so
#   python3-hapticd  (python)  the Python SDK, for Debian's python3
#   libhapticd-cil   (csharp)  the C# client (managed, over the HTTP face), for Mono
# Made with prefix /usr whatever the build was configured with: the DEB generator installs each
# component with CMAKE_INSTALL_PREFIX=/usr under a DESTDIR of its own, so the install rules that
# decide at install time (the configuration's /etc, the unit's ExecStart, the Python package's
# dist-packages) see /usr. Run `cpack -G DEB` in a build, or scripts/package.

set(HAPTIC_PACKAGE_MAINTAINER "hapticd maintainers <maintainers@hapticd.invalid>" CACHE STRING
    "The Maintainer field of the Debian packages (set a real address before publishing them)")
set(HAPTIC_PACKAGE_RELEASE 1 CACHE STRING "The Debian revision of the packages (0.1.0-<this>)")

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME hapticd)
set(CPACK_PACKAGE_VENDOR hapticd)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_CONTACT "${HAPTIC_PACKAGE_MAINTAINER}")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
set(CPACK_PACKAGE_DIRECTORY ${CMAKE_BINARY_DIR}/packages)

set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # name_version-release_arch.deb
set(CPACK_DEBIAN_PACKAGE_RELEASE ${HAPTIC_PACKAGE_RELEASE})
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
# dpkg-shlibdeps works out each package's shared libraries' packages (dpkg-dev and file, which
# scripts/setup installs); libhaptic-c1 gets a shlibs file, so that a package built against it
# depends on it.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_GENERATE_SHLIBS ON)
set(CPACK_DEBIAN_PACKAGE_GENERATE_SHLIBS_POLICY ">=")
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
set(haptic_deb_version "${PROJECT_VERSION}-${HAPTIC_PACKAGE_RELEASE}")

set(CPACK_COMPONENTS_ALL server tools c dev)

# Descriptions: a synopsis, then lines of at most 79 characters that cpack indents by one space
# (an empty line becomes the " ." between paragraphs).
# Every package's /usr/share/doc/<package>/copyright (machine-readable, DEP-5) and
# changelog.Debian.gz (gzip -9n: the same bytes on every build), as Debian policy 12.5 and 12.7
# ask and lintian checks (tests/packaging/deb_install_test.sh runs it on every package).
set(haptic_deb_doc_dir ${CMAKE_BINARY_DIR}/packaging/debian)
configure_file(${CMAKE_CURRENT_LIST_DIR}/common/copyright ${haptic_deb_doc_dir}/copyright @ONLY)
configure_file(${CMAKE_CURRENT_LIST_DIR}/common/changelog.in ${haptic_deb_doc_dir}/changelog @ONLY)
execute_process(COMMAND gzip -9nc ${haptic_deb_doc_dir}/changelog
                OUTPUT_FILE ${haptic_deb_doc_dir}/changelog.Debian.gz COMMAND_ERROR_IS_FATAL ANY)
function(haptic_deb_docs component package)
  install(FILES ${haptic_deb_doc_dir}/copyright ${haptic_deb_doc_dir}/changelog.Debian.gz
          DESTINATION ${CMAKE_INSTALL_DATAROOTDIR}/doc/${package} COMPONENT ${component})
endfunction()
haptic_deb_docs(server hapticd)
haptic_deb_docs(tools hapticd-tools)
haptic_deb_docs(c libhaptic-c1)
haptic_deb_docs(dev libhapticd-dev)
set(CPACK_DEBIAN_SERVER_PACKAGE_NAME hapticd)
set(CPACK_DEBIAN_SERVER_PACKAGE_SECTION science)
set(CPACK_COMPONENT_SERVER_DESCRIPTION "networked haptic server
hapticd runs a haptic device's control loop (a simulated point mass, or a
device through a driver) and serves it to clients over gRPC and UDP: walls,
springs, meshes and force fields rendered at the loop's rate.

This package holds the server, its default configuration
(/etc/hapticd/config.json), the systemd unit (installed, not enabled), the
hapticd system account (sysusers.d), the viewer's web page, the device drivers
and haptic-driver-kit.")
# The account and /run/hapticd: systemd-sysusers and systemd-tmpfiles where systemd is installed,
# useradd (passwd) and install(1) where it is not, as in a container.
set(CPACK_DEBIAN_SERVER_PACKAGE_DEPENDS "passwd")
set(CPACK_DEBIAN_SERVER_PACKAGE_SUGGESTS "hapticd-tools")
set(CPACK_DEBIAN_SERVER_PACKAGE_CONTROL_EXTRA
    ${CMAKE_CURRENT_LIST_DIR}/hapticd/postinst ${CMAKE_CURRENT_LIST_DIR}/hapticd/prerm
    ${CMAKE_CURRENT_LIST_DIR}/hapticd/postrm ${CMAKE_CURRENT_LIST_DIR}/hapticd/conffiles)

set(CPACK_DEBIAN_TOOLS_PACKAGE_NAME hapticd-tools)
set(CPACK_DEBIAN_TOOLS_PACKAGE_SECTION science)
set(CPACK_COMPONENT_TOOLS_DESCRIPTION "hapticd's command-line clients
hapticctl looks at and administers a running hapticd (status, sessions, stats,
events, scene, kick, record); touch_wall and multi_user are the SDK's example
clients. None needs the server on the same machine.")

set(CPACK_DEBIAN_C_PACKAGE_NAME libhaptic-c1)
set(CPACK_DEBIAN_C_PACKAGE_SECTION libs)
# The loader cache through dpkg's ldconfig trigger (lintian: lacks-ldconfig-trigger).
set(CPACK_DEBIAN_C_PACKAGE_CONTROL_EXTRA ${CMAKE_CURRENT_LIST_DIR}/libhaptic-c1/triggers)
set(CPACK_COMPONENT_C_DESCRIPTION "hapticd client SDK, C API (runtime)
libhaptic_c.so.1: the hapticd client SDK behind a C ABI (haptic/haptic_c.h),
for C programs and for languages that load a C library (C# P/Invoke, MATLAB
loadlibrary).")

set(CPACK_DEBIAN_DEV_PACKAGE_NAME libhapticd-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
# What the exported targets and hapticdConfig.cmake need: gRPC's and protobuf's CMake packages
# and libraries (haptic::proto links them), OpenSSL (the SDK), and the C runtime for the namelink.
# protobuf-compiler-grpc because Debian 12's gRPC CMake package (libgrpc++-dev's gRPCTargets.cmake)
# fails find_package without /usr/bin/grpc_cpp_plugin, which it does not depend on.
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS "libhaptic-c1 (= ${haptic_deb_version}), libgrpc++-dev, protobuf-compiler-grpc, libprotobuf-dev, libssl-dev")
if(TARGET haptic_recorder)  # haptic::recorder links HDF5 (find_dependency(HDF5) in the package)
  string(APPEND CPACK_DEBIAN_DEV_PACKAGE_DEPENDS ", libhdf5-dev")
endif()
set(CPACK_COMPONENT_DEV_DESCRIPTION "hapticd client SDK, development files
The headers (haptic/*.hpp, the C API's haptic/haptic_c.h, the driver ABI's
haptic/driver.h), the static SDK (haptic::sdk), the C API's link (haptic::c,
-lhaptic_c) and the CMake package: find_package(hapticd CONFIG). The C example
in /usr/share/doc/libhapticd-dev/examples.")

# The C example, built against the installed package as its header says (cc touch_wall.c
# -lhaptic_c -lm).
install(FILES ${PROJECT_SOURCE_DIR}/examples/c/touch_wall.c
        DESTINATION ${CMAKE_INSTALL_DATAROOTDIR}/doc/libhapticd-dev/examples COMPONENT dev)

# Python: only where python/ built the module, for the python3 it was built for.
if(TARGET haptic_python)
  list(APPEND CPACK_COMPONENTS_ALL python)
  execute_process(COMMAND ${Python_EXECUTABLE} -c "import sys; print('%d.%d' % sys.version_info[:2])"
                  OUTPUT_VARIABLE haptic_python_version OUTPUT_STRIP_TRAILING_WHITESPACE
                  COMMAND_ERROR_IS_FATAL ANY)
  string(REPLACE "." ";" haptic_python_next "${haptic_python_version}")
  list(GET haptic_python_next 1 haptic_python_minor)
  math(EXPR haptic_python_minor "${haptic_python_minor} + 1")
  list(GET haptic_python_next 0 haptic_python_major)
  set(CPACK_DEBIAN_PYTHON_PACKAGE_NAME python3-hapticd)
  set(CPACK_DEBIAN_PYTHON_PACKAGE_SECTION python)
  # The module is built for one CPython (_native.cpython-3XY-...so); the package imports numpy.
  set(CPACK_DEBIAN_PYTHON_PACKAGE_DEPENDS "python3 (>= ${haptic_python_version}~), \
python3 (<< ${haptic_python_major}.${haptic_python_minor}), python3-numpy")
  set(CPACK_COMPONENT_PYTHON_DESCRIPTION "hapticd client SDK for Python
The hapticd package (import hapticd): the client SDK for Python
${haptic_python_version}, with its type stubs. Examples in
/usr/share/doc/python3-hapticd/examples.")
  set(CPACK_DEBIAN_PYTHON_PACKAGE_CONTROL_EXTRA ${CMAKE_CURRENT_LIST_DIR}/python3-hapticd/postinst
      ${CMAKE_CURRENT_LIST_DIR}/python3-hapticd/prerm)
  install(FILES ${PROJECT_SOURCE_DIR}/examples/python/touch_wall.py
          DESTINATION ${CMAKE_INSTALL_DATAROOTDIR}/doc/python3-hapticd/examples COMPONENT python)
  haptic_deb_docs(python python3-hapticd)
endif()

# C#: where Mono's compiler built the client (bindings/). Managed code alone: one package for every
# architecture, needing Mono's runtime and the two assemblies it references.
if(TARGET haptic_csharp)
  list(APPEND CPACK_COMPONENTS_ALL csharp)
  set(CPACK_DEBIAN_CSHARP_PACKAGE_NAME libhapticd-cil)
  set(CPACK_DEBIAN_CSHARP_PACKAGE_SECTION cli-mono)
  set(CPACK_DEBIAN_CSHARP_PACKAGE_ARCHITECTURE all)
  set(CPACK_DEBIAN_CSHARP_PACKAGE_SHLIBDEPS OFF)
  set(CPACK_DEBIAN_CSHARP_PACKAGE_DEPENDS "mono-runtime (>= 6.8), libmono-corlib4.5-cil, libmono-system4.0-cil")
  set(CPACK_COMPONENT_CSHARP_DESCRIPTION "hapticd client SDK for C# (Mono)
Hapticd.dll in /usr/lib/cli/hapticd: the hapticd client in managed code alone
(.NET Standard 2.1 C#, no native library): the control plane over hapticd's
HTTP face, the state stream over UDP, events over WebSocket. The same sources
are the Unity package's runtime. The C# touch_wall in
/usr/share/doc/libhapticd-cil/examples (MONO_PATH=/usr/lib/cli/hapticd).")
  haptic_deb_docs(csharp libhapticd-cil)
endif()

include(CPack)
