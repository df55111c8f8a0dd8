# `cpack -G DEB` in the build directory makes zeroset_VERSION_ARCH.deb of everything
# `cmake --install` installs: the program, its bash completion, the headers, the static
# libraries with the CMake package, the license and the documentation. dpkg-shlibdeps (from
# dpkg-dev) finds the packages of the shared libraries the program links for Depends.
# The libraries and the program are built for the building machine's processor unless
# ZEROSET_NATIVE is OFF: configure with -DZEROSET_NATIVE=OFF for a package other machines install.
set(ZEROSET_PACKAGE_MAINTAINER "zeroset developers <dev@zeroset.invalid>"
    CACHE STRING "The Maintainer field of the Debian package")

set(CPACK_PACKAGE_NAME zeroset)
set(CPACK_PACKAGE_VENDOR "the zeroset authors")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "make implicit surfaces F(x, y, z) = 0 visible, singular points included")
set(CPACK_PACKAGE_CONTACT ${ZEROSET_PACKAGE_MAINTAINER})
set(CPACK_RESOURCE_FILE_LICENSE ${PROJECT_SOURCE_DIR}/LICENSE)
set(CPACK_RESOURCE_FILE_README ${PROJECT_SOURCE_DIR}/README.md)
set(CPACK_GENERATOR DEB)
set(CPACK_STRIP_FILES ON)

set(CPACK_DEBIAN_PACKAGE_MAINTAINER ${ZEROSET_PACKAGE_MAINTAINER})
set(CPACK_DEBIAN_PACKAGE_SECTION math)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# What find_package(zeroset) finds besides zeroset itself: only programs built against the
# library need these.
set(CPACK_DEBIAN_PACKAGE_SUGGESTS
    "g++ (>= 4:12), cmake (>= 3.25), libeigen3-dev, libfmt-dev, nlohmann-json3-dev, zlib1g-dev")
# The long description; cpack puts CPACK_PACKAGE_DESCRIPTION_SUMMARY before it as the synopsis.
set(CPACK_DEBIAN_PACKAGE_DESCRIPTION
    "zeroset draws, samples and meshes implicit surfaces given by an equation or taken
from its catalog (Kummer, Cayley, Clebsch, Barth's sextic, Whitney's umbrella,
...), singular points and self-intersections included: an exact ray tracer,
floating particles and marching cubes with a mesh improver, from the command line
(zeroset) or in an interactive viewer (zeroset view, when built with it).
.
The package also holds the C++ library (static libraries, headers and a CMake
package: find_package(zeroset), target zeroset::zeroset).")

include(CPack)
