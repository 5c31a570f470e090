# Finds CHAI3D 3.3 for the CHAI3D layer, building it once from source when the user has no build.
#
# CHAI3D is in no package registry. In order of preference:
#   1. CHAI3D_DIR (cache or environment): an existing CHAI3D 3.3 build tree, what a lab that already
#      uses CHAI3D has (the folder holding chai3dConfig.cmake).
#   2. CHAI3D_SOURCE (cache or environment): a CHAI3D 3.3.0 source archive (.tar.xz/.tar.gz/.zip) or
#      an unpacked source folder. An archive is checked against CHAI3D_SOURCE_SHA256, or against the
#      "<archive>.sha256" file beside it, when either is given.
#   3. Otherwise the public repository chai3d/chai3d at the 3.3.0 release commit, fetched the way
#      CMake projects fetch a pinned dependency (FetchContent). Without network this fails within
#      seconds with a message naming these choices and the opt-out.
# In cases 2 and 3 CHAI3D's own CMake builds its "chai3d" library (Release, its own flags) into
# UHAPTICS_CHAI3D_CACHE at configure time, once: a stamp records which source it came from, so a
# re-configure or a rebuild of uhaptics reuses it, and build trees that name the same cache folder
# (tools/run-tests: plain, ASan+UBSan, TSan) share one CHAI3D build. A CHAI3D built without
# sanitizers links into the sanitized uhaptics builds as any uninstrumented library does.
#
# uhaptics_provide_chai3d() sets CHAI3D_DIR (the build tree to find_package from; a normal variable,
# so the cache keeps what the user gave), UHAPTICS_CHAI3D_ORIGIN (for the configure message) and
# UHAPTICS_CHAI3D_BUILT (true when the CHAI3D is uhaptics' own build, which the installation ships).

set(UHAPTICS_CHAI3D_VERSION 3.3.0)
set(UHAPTICS_CHAI3D_REPOSITORY "https://github.com/chai3d/chai3d.git")
set(UHAPTICS_CHAI3D_COMMIT 7c76b1f)  # "Release 3.3.0"

foreach(_var CHAI3D_DIR CHAI3D_SOURCE CHAI3D_SOURCE_SHA256)
  if(NOT ${_var} AND DEFINED ENV{${_var}})
    set(${_var} "$ENV{${_var}}")
  endif()
endforeach()
set(CHAI3D_DIR "${CHAI3D_DIR}" CACHE PATH "An existing CHAI3D 3.3 build tree (the folder holding chai3dConfig.cmake)")
set(CHAI3D_SOURCE "${CHAI3D_SOURCE}" CACHE FILEPATH "CHAI3D 3.3.0 source archive or folder, built by uhaptics when CHAI3D_DIR is not set")
set(CHAI3D_SOURCE_SHA256 "${CHAI3D_SOURCE_SHA256}" CACHE STRING "Expected sha256 of the CHAI3D_SOURCE archive (optional)")
set(UHAPTICS_CHAI3D_CACHE "${CMAKE_BINARY_DIR}/_chai3d" CACHE PATH
    "Where uhaptics builds CHAI3D when CHAI3D_DIR is not set; build trees that name the same folder share one CHAI3D build")

# The message every failure ends with: the three ways to provide CHAI3D and the opt-out.
set(_uh_chai3d_ways
    "Provide CHAI3D in one of three ways:\n"
    "  -DCHAI3D_DIR=<an existing CHAI3D 3.3 build tree>        (or CHAI3D_DIR in the environment)\n"
    "  -DCHAI3D_SOURCE=<chai3d-3.3.0 source .tar.xz or folder> (or CHAI3D_SOURCE in the environment)\n"
    "  network access to ${UHAPTICS_CHAI3D_REPOSITORY} (commit ${UHAPTICS_CHAI3D_COMMIT} is fetched)\n"
    "or build without the CHAI3D layer: -DUHAPTICS_WITH_CHAI3D=OFF")

# _uh_chai3d_fail(<text>...): the pieces are joined into one message.
function(_uh_chai3d_fail)
  string(CONCAT _what ${ARGV})
  string(CONCAT _ways ${_uh_chai3d_ways})
  message(FATAL_ERROR "uhaptics: ${_what}\n${_ways}")
endfunction()

# Unpacks or fetches the CHAI3D source into <cache>/source; sets <out_dir> to the source folder and
# <out_id> to a string that identifies it (for the stamp).
function(_uh_chai3d_obtain_source out_dir out_id)
  set(_cache "${UHAPTICS_CHAI3D_CACHE}")
  if(CHAI3D_SOURCE)
    get_filename_component(_source "${CHAI3D_SOURCE}" ABSOLUTE)
    if(IS_DIRECTORY "${_source}")
      if(NOT EXISTS "${_source}/src/chai3d.h" OR NOT EXISTS "${_source}/CMakeLists.txt")
        _uh_chai3d_fail("CHAI3D_SOURCE=${_source} is a folder without CHAI3D's sources (no src/chai3d.h)")
      endif()
      set(${out_dir} "${_source}" PARENT_SCOPE)
      set(${out_id} "folder ${_source}" PARENT_SCOPE)
      return()
    endif()
    if(NOT EXISTS "${_source}")
      _uh_chai3d_fail("CHAI3D_SOURCE=${_source} does not exist")
    endif()
    file(SHA256 "${_source}" _actual)
    set(_expected "${CHAI3D_SOURCE_SHA256}")
    if(NOT _expected AND EXISTS "${_source}.sha256")
      file(STRINGS "${_source}.sha256" _line LIMIT_COUNT 1)
      string(REGEX MATCH "^[0-9a-fA-F]+" _expected "${_line}")
    endif()
    if(_expected AND NOT _actual STREQUAL _expected)
      _uh_chai3d_fail("CHAI3D_SOURCE=${_source} has sha256 ${_actual}, expected ${_expected}")
    endif()
    set(_id "archive sha256 ${_actual}")
    if(EXISTS "${_cache}/source/src/chai3d.h" AND EXISTS "${_cache}/source.id")
      file(READ "${_cache}/source.id" _old)
      if(_old STREQUAL _id)
        set(${out_dir} "${_cache}/source" PARENT_SCOPE)
        set(${out_id} "${_id}" PARENT_SCOPE)
        return()
      endif()
    endif()
    message(STATUS "uhaptics: unpacking CHAI3D from ${_source}")
    file(REMOVE_RECURSE "${_cache}/source" "${_cache}/unpack")
    file(ARCHIVE_EXTRACT INPUT "${_source}" DESTINATION "${_cache}/unpack")
    file(GLOB _top LIST_DIRECTORIES true "${_cache}/unpack/*")
    list(LENGTH _top _count)
    if(NOT _count EQUAL 1 OR NOT EXISTS "${_top}/src/chai3d.h")
      _uh_chai3d_fail("CHAI3D_SOURCE=${_source} does not unpack to one CHAI3D source folder")
    endif()
    file(RENAME "${_top}" "${_cache}/source")
    file(REMOVE_RECURSE "${_cache}/unpack")
    file(WRITE "${_cache}/source.id" "${_id}")
    set(${out_dir} "${_cache}/source" PARENT_SCOPE)
    set(${out_id} "${_id}" PARENT_SCOPE)
    return()
  endif()

  # The public repository. Ask it first, with a short timeout, so that a machine without network
  # gets the choices at once instead of a clone that hangs.
  set(_id "git ${UHAPTICS_CHAI3D_REPOSITORY} ${UHAPTICS_CHAI3D_COMMIT}")
  if(NOT (EXISTS "${_cache}/source/src/chai3d.h" AND EXISTS "${_cache}/source.id"))
    find_package(Git QUIET)
    if(NOT GIT_EXECUTABLE)
      _uh_chai3d_fail("neither CHAI3D_DIR nor CHAI3D_SOURCE is set, and git is not installed to fetch CHAI3D")
    endif()
    execute_process(COMMAND "${GIT_EXECUTABLE}" ls-remote --heads "${UHAPTICS_CHAI3D_REPOSITORY}"
                    RESULT_VARIABLE _rc OUTPUT_QUIET ERROR_VARIABLE _err TIMEOUT 20)
    if(NOT _rc EQUAL 0)
      string(STRIP "${_err}" _err)
      _uh_chai3d_fail("neither CHAI3D_DIR nor CHAI3D_SOURCE is set, and ${UHAPTICS_CHAI3D_REPOSITORY} "
                      "cannot be reached (${_rc}: ${_err})")
    endif()
    message(STATUS "uhaptics: fetching CHAI3D ${UHAPTICS_CHAI3D_VERSION} (${UHAPTICS_CHAI3D_COMMIT}) from ${UHAPTICS_CHAI3D_REPOSITORY}")
    include(FetchContent)
    FetchContent_Populate(uhaptics_chai3d
      GIT_REPOSITORY "${UHAPTICS_CHAI3D_REPOSITORY}"
      GIT_TAG "${UHAPTICS_CHAI3D_COMMIT}"
      SOURCE_DIR "${_cache}/source"
      SUBBUILD_DIR "${_cache}/fetch"
      BINARY_DIR "${_cache}/fetch-unused"
      QUIET)
    file(WRITE "${_cache}/source.id" "${_id}")
  endif()
  set(${out_dir} "${_cache}/source" PARENT_SCOPE)
  set(${out_id} "${_id}" PARENT_SCOPE)
endfunction()

function(uhaptics_provide_chai3d)
  if(CHAI3D_DIR)
    set(UHAPTICS_CHAI3D_ORIGIN "the CHAI3D build given by CHAI3D_DIR" PARENT_SCOPE)
    set(UHAPTICS_CHAI3D_BUILT FALSE PARENT_SCOPE)
    return()
  endif()
  set(UHAPTICS_CHAI3D_BUILT TRUE PARENT_SCOPE)

  set(_cache "${UHAPTICS_CHAI3D_CACHE}")
  file(MAKE_DIRECTORY "${_cache}")
  # Two configures sharing the cache (parallel build trees) build CHAI3D once.
  file(LOCK "${_cache}/.lock" GUARD FUNCTION TIMEOUT 3600)
  _uh_chai3d_obtain_source(_source _id)

  set(_build "${_cache}/build")
  set(_stamp "${_build}/uhaptics-built-from.txt")
  if(EXISTS "${_stamp}" AND EXISTS "${_build}/chai3dConfig.cmake")
    file(READ "${_stamp}" _built)
    if(_built STREQUAL _id)
      set(CHAI3D_DIR "${_build}" PARENT_SCOPE)
      set(UHAPTICS_CHAI3D_ORIGIN "the CHAI3D uhaptics built earlier from ${_id}" PARENT_SCOPE)
      return()
    endif()
  endif()

  include(ProcessorCount)
  ProcessorCount(_jobs)
  if(_jobs EQUAL 0)
    set(_jobs 2)
  endif()
  set(_log "${_cache}/build.log")
  message(STATUS "uhaptics: building CHAI3D ${UHAPTICS_CHAI3D_VERSION}'s library from ${_source} into ${_build} "
                 "(once; about 5 minutes on 2 cores; log: ${_log})")
  file(REMOVE_RECURSE "${_build}")
  # Only CHAI3D's library is built; its examples are compiled by uhaptics' drop-in tests.
  # CMAKE_EXPORT_NO_PACKAGE_REGISTRY: CHAI3D's export(PACKAGE) would otherwise register the build
  # in ~/.cmake for every other project on the machine.
  # The same C++ compiler as uhaptics (one libstdc++ ABI); CHAI3D's C sources take the default C
  # compiler (uhaptics itself compiles no C).
  execute_process(
    COMMAND "${CMAKE_COMMAND}" -S "${_source}" -B "${_build}" -G "${CMAKE_GENERATOR}"
            -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=${CMAKE_CXX_COMPILER}
            -DCMAKE_EXPORT_NO_PACKAGE_REGISTRY=ON
    RESULT_VARIABLE _rc OUTPUT_FILE "${_log}" ERROR_FILE "${_log}.err")
  if(_rc EQUAL 0)
    execute_process(COMMAND "${CMAKE_COMMAND}" --build "${_build}" --target chai3d -j ${_jobs}
                    RESULT_VARIABLE _rc OUTPUT_FILE "${_log}.build" ERROR_FILE "${_log}.err")
  endif()
  if(NOT _rc EQUAL 0)
    file(READ "${_log}.err" _err)
    string(LENGTH "${_err}" _length)
    if(_length GREATER 4000)
      math(EXPR _from "${_length} - 4000")
      string(SUBSTRING "${_err}" ${_from} 4000 _err)
    endif()
    _uh_chai3d_fail("building CHAI3D from ${_source} failed (${_rc}); see ${_log}*:\n${_err}\n"
                    "(CHAI3D needs Debian's libgl1-mesa-dev libglu1-mesa-dev libusb-1.0-0-dev xorg-dev libasound2-dev)")
  endif()
  file(WRITE "${_stamp}" "${_id}")
  set(CHAI3D_DIR "${_build}" PARENT_SCOPE)
  set(UHAPTICS_CHAI3D_ORIGIN "CHAI3D built by uhaptics from ${_id}" PARENT_SCOPE)
endfunction()

# uhaptics_chai3d_link_items(): what linking CHAI3D takes, read from chai3dConfig.cmake's
# CHAI3D_LIBRARIES, in a form that holds both in this build and in the installed package. CHAI3D's
# own libraries (its archive and the Force Dimension SDK it ships, libdrd.a) are files. The rest are
# system libraries, which a consumer must find on its own machine: GL, GLU, pthread and ALSA become
# the imported targets of CMake's find modules (found here, at the top level, so every folder sees
# them; the installed uhapticsConfig.cmake finds them again), libusb the pkg-config target
# uhaptics::protocol uses, and any other name (rt, dl) stays a name for the linker. Sets:
#   UHAPTICS_CHAI3D_OWN_LIBRARIES     CHAI3D's own library files, in link order
#   UHAPTICS_CHAI3D_SYSTEM_LIBRARIES  the system libraries as targets or names, in link order
#   UHAPTICS_CHAI3D_PACKAGES          the find modules those targets come from
#   UHAPTICS_CHAI3D_SYSTEM_TARGETS    the targets among them
function(uhaptics_chai3d_link_items)
  set(_archive "")
  foreach(_config RELEASE RELWITHDEBINFO MINSIZEREL DEBUG NOCONFIG)
    get_target_property(_location chai3d IMPORTED_LOCATION_${_config})
    if(_location AND NOT _archive)
      set(_archive "${_location}")
    endif()
  endforeach()
  if(NOT EXISTS "${_archive}")
    message(FATAL_ERROR "uhaptics: CHAI3D's config in ${chai3d_DIR} names no built library: build CHAI3D "
                        "first (its target 'chai3d')")
  endif()
  set(_own "")
  set(_system "")
  set(_packages "")
  foreach(_lib IN LISTS CHAI3D_LIBRARIES)
    if(_lib STREQUAL "chai3d")
      list(APPEND _own "${_archive}")
      continue()
    elseif(_lib STREQUAL "drd")  # Force Dimension's prebuilt static SDK, referenced by CDeltaDevices
      find_library(UHAPTICS_CHAI3D_DRD NAMES libdrd.a drd PATHS ${CHAI3D_LIBRARY_DIRS} NO_DEFAULT_PATH REQUIRED)
      list(APPEND _own "${UHAPTICS_CHAI3D_DRD}")
      continue()
    endif()
    if(IS_ABSOLUTE "${_lib}")
      set(_inside FALSE)
      foreach(_tree IN ITEMS "${CHAI3D_SOURCE_DIR}" "${chai3d_DIR}")
        string(FIND "${_lib}" "${_tree}/" _at)
        if(_tree AND _at EQUAL 0)
          set(_inside TRUE)
        endif()
      endforeach()
      if(_inside)
        list(APPEND _own "${_lib}")
        continue()
      endif()
      get_filename_component(_name "${_lib}" NAME)
      string(REGEX REPLACE "^lib|\\.(so|a)(\\.[0-9.]*)?$" "" _name "${_name}")
    else()
      string(REGEX REPLACE "^-l" "" _name "${_lib}")
    endif()
    if(_name MATCHES "^(GL|OpenGL)$")
      find_package(OpenGL REQUIRED)
      list(APPEND _system OpenGL::GL)
      list(APPEND _packages OpenGL)
    elseif(_name STREQUAL "GLU")
      find_package(OpenGL REQUIRED)
      if(NOT TARGET OpenGL::GLU)
        message(FATAL_ERROR "uhaptics: CHAI3D links GLU, which is not installed (Debian: libglu1-mesa-dev)")
      endif()
      list(APPEND _system OpenGL::GLU)
      list(APPEND _packages OpenGL)
    elseif(_name STREQUAL "pthread")
      find_package(Threads REQUIRED)
      list(APPEND _system Threads::Threads)
      list(APPEND _packages Threads)
    elseif(_name STREQUAL "asound")
      find_package(ALSA REQUIRED)
      list(APPEND _system ALSA::ALSA)
      list(APPEND _packages ALSA)
    elseif(_name STREQUAL "usb-1.0")
      list(APPEND _system PkgConfig::LIBUSB)  # devices/protocol finds it; so does uhapticsConfig.cmake
    else()
      list(APPEND _system "${_name}")
    endif()
  endforeach()
  list(REMOVE_DUPLICATES _system)
  list(REMOVE_DUPLICATES _packages)
  set(_targets "${_system}")
  list(FILTER _targets INCLUDE REGEX "::")
  set(UHAPTICS_CHAI3D_OWN_LIBRARIES "${_own}" PARENT_SCOPE)
  set(UHAPTICS_CHAI3D_SYSTEM_LIBRARIES "${_system}" PARENT_SCOPE)
  set(UHAPTICS_CHAI3D_PACKAGES "${_packages}" PARENT_SCOPE)
  set(UHAPTICS_CHAI3D_SYSTEM_TARGETS "${_targets}" PARENT_SCOPE)
endfunction()
