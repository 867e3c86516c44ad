// Subcommands of the `semrec` CLI. Each Register* adds its CLI11 subcommand and
// the callback that runs it; callbacks throw semrec::Error on bad input, which
// main() turns into "error: ..." + exit 1.
#pragma once

#include <CLI/CLI.hpp>

namespace semrec::cli {

void RegisterInfo(CLI::App& app);
void RegisterTsdf(CLI::App& app);
void RegisterSynth(CLI::App& app);
void RegisterFuse(CLI::App& app);
void RegisterEval(CLI::App& app);

}  // namespace semrec::cli
