// `import dynahand`: the Python binding (docs/python.md). Tracker, sequences on disk, synthetic
// clips in memory, the accuracy metrics of `dynahand eval` and the detector's training data, on
// numpy arrays. Each part is bound by its own file (module_util.h lists them); bad input is a
// ValueError, a file problem an OSError (FileNotFoundError for a missing path), each carrying
// the library's message; nothing here asserts on user input.
#include <exception>

#include "module_util.h"

PYBIND11_MODULE(dynahand, m) {
  using namespace dynahand::python;
  m.doc() =
      "dynahand: dynamics-based 3D skeletal hand tracking from depth images (docs/python.md).\n"
      "Metres, camera frame as OpenCV (x right, y down, z forward); keypoints in MediaPipe order.";
  m.attr("__version__") = DYNAHAND_VERSION;

  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const FileMissing& e) {
      PyErr_SetString(PyExc_FileNotFoundError, e.what());
    } catch (const FileError& e) {
      PyErr_SetString(PyExc_OSError, e.what());
    }
  });

  bindCamera(m);
  bindTracker(m);
  bindSequence(m);
  bindSynth(m);
  bindMetrics(m);
  bindDetectorData(m);
}
