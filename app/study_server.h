// `sirl study serve` and `sirl study import`: the web study and answers collected elsewhere.
#pragma once

namespace CLI {
class App;
}

namespace sirl::app {

void register_study_serve(CLI::App& study);
void register_study_import(CLI::App& study);
// Runs whichever of serve / import was parsed.
int run_study_serve_or_import();

}  // namespace sirl::app
