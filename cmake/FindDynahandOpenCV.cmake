# Finds the three OpenCV components dynahand uses (core, imgproc, imgcodecs) from
# Debian's per-module -dev packages, so the whole libopencv-dev (GUI, VTK, ...) is
# not needed. Defines the imported target DynahandOpenCV::OpenCV, and
# DynahandOpenCV::VideoIO when libopencv-videoio-dev is there (MP4 output of the command).
find_path(DynahandOpenCV_INCLUDE_DIR opencv2/core.hpp PATH_SUFFIXES opencv4)
find_library(DynahandOpenCV_core_LIBRARY opencv_core)
find_library(DynahandOpenCV_imgproc_LIBRARY opencv_imgproc)
find_library(DynahandOpenCV_imgcodecs_LIBRARY opencv_imgcodecs)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(DynahandOpenCV REQUIRED_VARS DynahandOpenCV_INCLUDE_DIR
  DynahandOpenCV_core_LIBRARY DynahandOpenCV_imgproc_LIBRARY DynahandOpenCV_imgcodecs_LIBRARY)
if(DynahandOpenCV_FOUND AND NOT TARGET DynahandOpenCV::OpenCV)
  add_library(DynahandOpenCV::OpenCV INTERFACE IMPORTED)
  set_target_properties(DynahandOpenCV::OpenCV PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES "${DynahandOpenCV_INCLUDE_DIR}"
    INTERFACE_LINK_LIBRARIES "${DynahandOpenCV_imgcodecs_LIBRARY};${DynahandOpenCV_imgproc_LIBRARY};${DynahandOpenCV_core_LIBRARY}")
endif()

find_library(DynahandOpenCV_videoio_LIBRARY opencv_videoio)
if(DynahandOpenCV_FOUND AND DynahandOpenCV_videoio_LIBRARY AND NOT TARGET DynahandOpenCV::VideoIO)
  add_library(DynahandOpenCV::VideoIO INTERFACE IMPORTED)
  set_target_properties(DynahandOpenCV::VideoIO PROPERTIES
    INTERFACE_LINK_LIBRARIES "${DynahandOpenCV_videoio_LIBRARY};DynahandOpenCV::OpenCV")
endif()

# The learned detector's inference (libopencv-dnn-dev): DynahandOpenCV::DNN.
find_library(DynahandOpenCV_dnn_LIBRARY opencv_dnn)
if(DynahandOpenCV_FOUND AND DynahandOpenCV_dnn_LIBRARY AND NOT TARGET DynahandOpenCV::DNN)
  add_library(DynahandOpenCV::DNN INTERFACE IMPORTED)
  set_target_properties(DynahandOpenCV::DNN PROPERTIES
    INTERFACE_LINK_LIBRARIES "${DynahandOpenCV_dnn_LIBRARY};DynahandOpenCV::OpenCV")
endif()
