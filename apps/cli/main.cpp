// aperture: render triangle meshes through Embree ray packets into multi-channel EXR files.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <csignal>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "apps/cli/commands.h"
#include "core/util/error.h"
#include "core/util/spelling.h"

namespace {

/// The first "--flag" of argv that `sub` does not know, with the closest known flag; "" when
/// every flag is known.
std::string unknownFlagMessage(const CLI::App& sub, int argc, char** argv) {
  std::vector<std::string> known;
  for (const CLI::Option* o : sub.get_options())
    for (const std::string& n : o->get_lnames()) known.push_back("--" + n);
  for (int k = 2; k < argc; ++k) {
    std::string word = argv[k];
    if (word.rfind("--", 0) != 0 || word == "--") continue;
    word = word.substr(0, word.find('='));
    if (std::find(known.begin(), known.end(), word) != known.end()) continue;
    return "aperture: unknown flag '" + word + "' for '" + sub.get_name() + "'" +
           aperture::didYouMean(word, known) + "; see aperture " + sub.get_name() + " --help";
  }
  return "";
}

using Commands = std::vector<std::pair<CLI::App*, aperture::app::Command>>;

/// Registers every subcommand on `app`.
Commands addCommands(CLI::App& app) {
  using namespace aperture::app;
  Commands commands;
  for (Command (*make)(CLI::App&) :
       {addRenderCommand, addBenchCommand, addBatchCommand, addCameraCommand, addTradeoffCommand,
        addVisibilityCommand, addScanCommand, addQueryCommand}) {
    const size_t before = app.get_subcommands({}).size();
    Command run = make(app);
    commands.emplace_back(app.get_subcommands({})[before], std::move(run));
  }
  return commands;
}

/// A first word that is no subcommand: says which word (with "did you mean") and lists the
/// commands; false when the word is a command or a flag.
bool reportUnknownCommand(const Commands& commands, int argc, char** argv) {
  if (argc < 2 || argv[1][0] == '-') return false;
  std::vector<std::string> names;
  for (const auto& c : commands) {
    if (c.first->get_name() == argv[1]) return false;
    names.push_back(c.first->get_name());
  }
  const std::string known = aperture::join(names, ", ");
  std::fprintf(stderr, "aperture: unknown command '%s'%s (known: %s); see aperture --help\n",
               argv[1], aperture::didYouMean(argv[1], names).c_str(), known.c_str());
  return true;
}

/// Parses the command line; the exit code of a usage error (2), --help/--version (0), or -1
/// to go on.
int parseCommandLine(CLI::App& app, const Commands& commands, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ExtrasError& e) {
    for (const auto& c : commands) {
      if (c.first->get_name() != argv[1]) continue;
      const std::string message = unknownFlagMessage(*c.first, argc, argv);
      if (message.empty()) break;
      std::fprintf(stderr, "%s\n", message.c_str());
      return 2;
    }
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const CLI::ParseError& e) {
    // --help/--version exit 0; every usage error (CLI11 uses codes such as 104 for a value
    // that does not convert) exits 2 with its message.
    return app.exit(e) == 0 ? 0 : 2;
  }
  return -1;
}

/// Runs the parsed subcommand: its exit code, or 1 with the error on stderr.
int runParsedCommand(const Commands& commands) {
  try {
    for (const auto& [sub, run] : commands)
      if (sub->parsed()) return run();
  } catch (const aperture::Error& e) {
    std::fprintf(stderr, "aperture: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "aperture: internal error: %s\n", e.what());
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Past a file-size limit (ulimit -f), write() should fail with EFBIG, which the atomic
  // writer reports and cleans up, instead of SIGXFSZ killing the process mid-write.
  std::signal(SIGXFSZ, SIG_IGN);
  CLI::App app{"aperture " APERTURE_VERSION
               ": batch-render and benchmark large triangle meshes with Embree ray packets"};
  app.set_version_flag("--version", "aperture " APERTURE_VERSION);
  app.require_subcommand(1);
  const Commands commands = addCommands(app);
  if (reportUnknownCommand(commands, argc, argv)) return 2;
  const int parsed = parseCommandLine(app, commands, argc, argv);
  return parsed >= 0 ? parsed : runParsedCommand(commands);
}
