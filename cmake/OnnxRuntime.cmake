# Imported target onnxruntime::onnxruntime from the folder that scripts/setup assembles
# (.deps/onnxruntime: official libonnxruntime.so.1 + Debian trixie headers). The library's folder
# goes into the rpath of everything that links it, so no LD_LIBRARY_PATH is needed.
set(_ort_lib "${SEMREC_ORT_ROOT}/lib/libonnxruntime.so.1")
set(_ort_inc "${SEMREC_ORT_ROOT}/include")
if(EXISTS "${_ort_lib}" AND EXISTS "${_ort_inc}/onnxruntime_cxx_api.h")
  add_library(onnxruntime::onnxruntime SHARED IMPORTED GLOBAL)
  set_target_properties(onnxruntime::onnxruntime PROPERTIES
    IMPORTED_LOCATION "${_ort_lib}"
    IMPORTED_SONAME "libonnxruntime.so.1"
    INTERFACE_INCLUDE_DIRECTORIES "${_ort_inc}"
    INTERFACE_LINK_OPTIONS "LINKER:-rpath,${SEMREC_ORT_ROOT}/lib")
  set(SEMREC_HAVE_ORT ON)
  message(STATUS "ONNX Runtime: ${_ort_lib}")
else()
  message(FATAL_ERROR "ONNX Runtime not found in ${SEMREC_ORT_ROOT} (expected lib/libonnxruntime.so.1 "
                      "and include/onnxruntime_cxx_api.h). Run scripts/setup first, or set "
                      "-DSEMREC_ORT_ROOT=<folder>.")
endif()
