#pragma once
// Subcommands of the `aperture` executable; each registers its options and returns the
// function that runs it (exit code).
#include <CLI/CLI.hpp>
#include <functional>

namespace aperture::app {

using Command = std::function<int()>;
Command addRenderCommand(CLI::App& app);
Command addBenchCommand(CLI::App& app);
Command addCameraCommand(CLI::App& app);
Command addBatchCommand(CLI::App& app);
Command addTradeoffCommand(CLI::App& app);
Command addVisibilityCommand(CLI::App& app);
Command addScanCommand(CLI::App& app);
Command addQueryCommand(CLI::App& app);

}  // namespace aperture::app
