# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
# Workaround for the ROS 2 PyPI wheels, included after rosidl_generate_interfaces by every
# interface package fourws builds (CMakeLists.txt, interfaces/*/CMakeLists.txt): the wheels'
# exported CMake targets carry include directories of the machine that built them (under
# /opt/python/...), which do not exist here and make CMake refuse to generate. Drop such
# non-existent entries. On a system ROS 2 every entry exists, so this changes nothing there.
get_directory_property(_fourws_imported IMPORTED_TARGETS)
foreach(_tgt IN LISTS _fourws_imported)
  get_target_property(_dirs ${_tgt} INTERFACE_INCLUDE_DIRECTORIES)
  if(_dirs)
    set(_kept "")
    foreach(_d IN LISTS _dirs)
      if(_d MATCHES "^/opt/python/" AND NOT EXISTS "${_d}")
        continue()
      endif()
      list(APPEND _kept "${_d}")
    endforeach()
    set_target_properties(${_tgt} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${_kept}")
  endif()
endforeach()
