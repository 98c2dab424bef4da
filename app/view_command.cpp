// `drape view` entry point: maps failures to the CLI's exit codes.
#include "view_command.hpp"

#include <cstdio>
#include <new>
#include <stdexcept>

#include "drape/errors.hpp"
#include "gl_context.hpp"
#include "view_app.hpp"

namespace drape::app {

int view_command(const ViewOptions& options) {
    try {
        Viewer viewer(options);
        return viewer.run();
    } catch (const render::DisplayError& e) {
        std::fprintf(stderr,
                     "drape view: no display to open a window on (%s); run it under a virtual X server: "
                     "xvfb-run -a -s \"-screen 0 1600x1000x24\" drape view --frames 300 --screenshot out.png "
                     "--stats-json (or scripts/run_viewer.sh)\n",
                     e.what());
        return exit_code::bad_input;
    } catch (const InvalidInput& e) {
        std::fprintf(stderr, "drape view: %s\n", e.what());
        return exit_code::bad_input;
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "drape view: out of memory building the scene; choose a smaller --size\n");
        return exit_code::bad_input;
    } catch (const WriteError& e) { // a screenshot (or another output) could not be written
        std::fprintf(stderr, "drape view: %s\n", e.what());
        return exit_code::write_failed;
    } catch (const BlowUpError& e) {
        std::fprintf(stderr, "drape view: %s\n", e.what());
        return exit_code::blow_up;
    } catch (const SimulationError& e) {
        std::fprintf(stderr, "drape view: %s\n", e.what());
        return exit_code::non_finite;
    } catch (const std::exception& e) { // OpenGL set-up failures and bugs: said plainly, never an abort
        std::fprintf(stderr, "drape view: internal error: %s\n", e.what());
        return exit_code::internal;
    }
}

} // namespace drape::app
