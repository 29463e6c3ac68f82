// Calibrations kept between processes: with SIRL_CALIBRATION_CACHE naming a folder, `sirl plan`
// (and every command that plans: run --budget, reproduce, submit) stores each environment's
// calibrated rates there and reuses them, instead of timing the training code again. A stored
// calibration is used only by the same binary (its bytes' digest) on the same CPU class
// (probes/cpu_class.h) for the same sample (what it calibrated), so it is what that process would
// have measured on an idle machine. For test suites and scripts that plan many times on one
// machine; unset, nothing is kept.
#pragma once
#include <optional>
#include <string>
#include <vector>

namespace sirl {

// The values stored for `what` (a canonical description of what was timed), or nothing: no
// folder set, none stored, or a file that does not read as one (never an error).
std::optional<std::vector<double>> load_calibration(const std::string& what);
// Stores `values` for `what` (written whole, atomically); does nothing without a folder set, and
// a folder that cannot be written is one warning line, never an error.
void save_calibration(const std::string& what, const std::vector<double>& values);

}  // namespace sirl
