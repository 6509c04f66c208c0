// `floorpose eval-compare BASE NEXT`: two eval-suite runs of the same walks, their figures
// and differences with 95% intervals (tools/lib/compare.h).
#include <spdlog/spdlog.h>

#include <cstdio>
#include <filesystem>

#include "tools/floorpose/commands.h"
#include "tools/lib/compare.h"

namespace floorpose::tools {
namespace {

std::string ResultsPath(const std::string& arg) {
  return std::filesystem::is_directory(arg) ? (std::filesystem::path(arg) / "results.json").string()
                                            : arg;
}

}  // namespace

Run AddEvalCompareCommand(CLI::App& app) {
  auto base = std::make_shared<std::string>(), next = std::make_shared<std::string>();
  auto resamples = std::make_shared<int>(2000);
  app.add_option("base", *base, "eval-suite --out directory (or its results.json) of the baseline")
      ->required();
  app.add_option("next", *next, "...and of the change, on the same walks")->required();
  app.add_option("--resamples", *resamples, "bootstrap draws")
      ->check(CLI::Range(100, 1000000))
      ->capture_default_str();
  return [=] {
    std::vector<RunFigures> a, b;
    for (auto [path, runs] : {std::pair{ResultsPath(*base), &a}, {ResultsPath(*next), &b}})
      if (const std::string error = ReadRuns(path, runs); !error.empty()) {
        spdlog::error("eval-compare: {}", error);
        return 1;
      }
    const std::vector<Difference> diffs = Compare(a, b, *resamples, 0x636f6d70);
    std::printf(
        "| figure | base | next | next - base | 95%% interval | |\n|---|---|---|---|---|---|\n");
    for (const Difference& d : diffs) {
      const double k = std::string(d.unit) == "%" ? 100.0 : 1.0;
      const char* verdict = d.low > 0 ? "higher" : d.high < 0 ? "lower" : "within noise";
      const int n = d.digits;
      std::printf("| %s | %.*f%s | %.*f%s | %+.*f | %+.*f to %+.*f | %s |\n", d.name, n, k * d.base,
                  d.unit, n, k * d.next, d.unit, n, k * (d.next - d.base), n, k * d.low, n,
                  k * d.high, verdict);
    }
    std::printf("\n%zu runs of the base, %zu of the next; paired on those of both.\n", a.size(),
                b.size());
    return 0;
  };
}

}  // namespace floorpose::tools
