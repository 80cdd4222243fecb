// aperture: render triangle meshes through Embree ray packets into multi-channel EXR files.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <csignal>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "core/error.h"
#include "core/spelling.h"

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

}  // namespace

int main(int argc, char** argv) {
  using namespace aperture::app;
  // Past a file-size limit (ulimit -f), write() should fail with EFBIG, which the atomic
  // writer reports and cleans up, instead of SIGXFSZ killing the process mid-write.
  std::signal(SIGXFSZ, SIG_IGN);
  CLI::App app{"aperture " APERTURE_VERSION
               ": batch-render and benchmark large triangle meshes with Embree ray packets"};
  app.set_version_flag("--version", "aperture " APERTURE_VERSION);
  app.require_subcommand(1);
  std::vector<std::pair<CLI::App*, Command>> commands;
  auto add = [&](Command (*make)(CLI::App&)) {
    const size_t before = app.get_subcommands({}).size();
    Command run = make(app);
    commands.emplace_back(app.get_subcommands({})[before], std::move(run));
  };
  add(addRenderCommand);
  add(addBenchCommand);
  add(addBatchCommand);
  add(addCameraCommand);
  add(addTradeoffCommand);
  // A first word that is no subcommand: say which word, and list the commands.
  std::string known;
  bool isCommand = false;
  for (const auto& c : commands) {
    known += (known.empty() ? "" : ", ") + c.first->get_name();
    isCommand = isCommand || (argc > 1 && c.first->get_name() == argv[1]);
  }
  if (argc > 1 && argv[1][0] != '-' && !isCommand) {
    std::vector<std::string> names;
    for (const auto& c : commands) names.push_back(c.first->get_name());
    std::fprintf(stderr, "aperture: unknown command '%s'%s (known: %s); see aperture --help\n",
                 argv[1], aperture::didYouMean(argv[1], names).c_str(), known.c_str());
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ExtrasError& e) {
    for (const auto& c : commands)
      if (argc > 1 && c.first->get_name() == argv[1]) {
        const std::string message = unknownFlagMessage(*c.first, argc, argv);
        if (!message.empty()) {
          std::fprintf(stderr, "%s\n", message.c_str());
          return 2;
        }
      }
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const CLI::ParseError& e) {
    // --help/--version exit 0; every usage error (CLI11 uses codes such as 104 for a value
    // that does not convert) exits 2 with its message.
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    for (auto& [sub, run] : commands)
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
