# The Debian package (CPack DEB): `cpack --config build/release/CPackConfig.cmake` after a release build, or
# `bash toolchain/host.sh package`. What goes in is what `cmake --install` lays out (bringup/CMakeLists.txt).
# Included from the top-level CMakeLists.txt (CPack wants its config in the top build folder).
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME ugvsense)
set(CPACK_PACKAGE_VENDOR "ugvsense")
set(CPACK_PACKAGE_CONTACT "ugvsense developers <ugvsense@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "real-time stereo obstacle service for unmanned ground vehicles")
set(CPACK_DEBIAN_PACKAGE_DESCRIPTION
    "ugvsensed captures a stereo camera pair, finds obstacles above and below the ground (ground-plane projection and
 semi-global matching) and publishes obstacle sectors over iceoryx and DDS within a per-frame deadline. With the
 ugvsense tool (calibration, recording, replay, latency budgets, the OOI correlator) and systemd units. Nothing is
 enabled at install: 'systemctl start ugvsensed' runs it on the embedded default recording.")
if(UGV_CPU_LEVEL AND NOT UGV_CPU_LEVEL STREQUAL "x86-64")
    # toolchain/cpu-level.cmake: the programs refuse, with this fix, to start on an older CPU.
    string(APPEND CPACK_DEBIAN_PACKAGE_DESCRIPTION
           "\n .\n Built for ${UGV_CPU_LEVEL} CPUs; for older x86-64 PCs build the package with -DUGV_CPU=x86-64.")
endif()
set(CPACK_PACKAGING_INSTALL_PREFIX ${CMAKE_INSTALL_PREFIX}) # the units name the programs by this prefix
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)                     # ugvsense_<version>_<arch>.deb
set(CPACK_DEBIAN_PACKAGE_SECTION misc)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
# Libraries from dpkg-shlibdeps; iox-roudi (a program, not linked) and adduser (postinst) by hand.
set(CPACK_DEBIAN_PACKAGE_DEPENDS "adduser, iceoryx (>= 2.0)")
# openssl: ugvsense-make-security (the secured bus's files); fastdds-tools: `fastdds shm clean` before each start of
# ugvsensed (the shared memory of a killed run).
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "openssl, fastdds-tools")
if(CMAKE_CROSSCOMPILING)
    # dpkg-shlibdeps cannot read the sysroot (an extract has no package database): the libraries by name, as
    # dpkg-shlibdeps gives them for the native package (bookworm's names are the same on every architecture).
    set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE arm64)
    string(APPEND CPACK_DEBIAN_PACKAGE_DEPENDS
           ", libc6 (>= 2.35), libstdc++6 (>= 11), libgcc-s1, libcamera0.0.3, libfastcdr1, libfastrtps2.9,"
           " libgeographiclib23, libiceoryx-hoofs2, libiceoryx-posh2, libiceoryx-posh-roudi2, libopencv-core406,"
           " libopencv-imgproc406, libopencv-calib3d406, libopencv-imgcodecs406, libsystemd0, libyaml-cpp0.7, zlib1g")
else()
    set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
endif()
set(CPACK_STRIP_FILES ON)
file(WRITE ${CMAKE_BINARY_DIR}/packaging/conffiles "/etc/ugvsense/config.yaml\n/etc/ugvsense/roudi.toml\n")
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    ${CMAKE_CURRENT_LIST_DIR}/postinst ${CMAKE_CURRENT_LIST_DIR}/prerm ${CMAKE_CURRENT_LIST_DIR}/postrm
    ${CMAKE_BINARY_DIR}/packaging/conffiles)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
set(CPACK_PACKAGE_DIRECTORY ${CMAKE_BINARY_DIR}/package)
include(CPack)
