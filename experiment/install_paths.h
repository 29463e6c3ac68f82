// Where the engine finds what ships beside the binary (the bundled profiles, the figure scripts,
// the results reader, the study page) and which Python runs the scripts, decided at run time so
// an installed `sirl` works wherever its prefix is moved and without the source folder.
#pragma once
#include <filesystem>
#include <string>

namespace sirl {

// The folder laid out like the source tree (configs/, results/, python/, app/study_web/):
//   1. $SIRL_DATA_DIR when set;
//   2. <the binary's folder>/../share/sirl-bench when it holds configs/ (an installed sirl);
//   3. the source folder this build was configured from (a build tree), unless
//      $SIRL_INSTALLED_ONLY is set (packagers and the install test: fail rather than fall back).
// Throws std::runtime_error when none holds configs/.
std::filesystem::path data_dir();

// The Python that runs the figure scripts: $SIRL_PYTHON when set, else the interpreter this build
// was configured with (CMake option SIRL_PYTHON, default Debian's /usr/bin/python3, which has the
// python3-h5py, -pandas, -matplotlib and -scipy packages the scripts need).
std::string python_interpreter();

}  // namespace sirl
