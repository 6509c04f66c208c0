#include "tools/lib/compare.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "core/random.h"
#include "tools/lib/evaluation.h"

namespace floorpose::tools {

SuiteFigures Figures(const std::vector<const RunFigures*>& runs) {
  SuiteFigures f;
  double scored = 0, reliable = 0, brier = 0;
  for (const RunFigures* r : runs) {
    f.mean_error_m += r->mean_error_m;
    f.runs_over_5m += r->max_error_m > 5.0;
    scored += r->scored_poses;
    reliable += r->reliable_poses;
    f.false_poses += r->false_poses;
    brier += r->brier * r->scored_poses;
    f.recovered += r->time_to_recovered_s >= 0 && r->time_to_recovered_s <= kBackAfterKidnapS;
    f.never_recovered += r->time_to_recovered_s < 0;
  }
  if (!runs.empty()) {
    f.mean_error_m /= static_cast<double>(runs.size());
    f.recovered /= static_cast<double>(runs.size());
  }
  f.reliable = scored > 0 ? reliable / scored : 0.0;
  f.precision = reliable > 0 ? 1.0 - f.false_poses / reliable : 1.0;
  f.brier = scored > 0 ? brier / scored : 0.0;
  return f;
}

std::vector<Difference> Compare(const std::vector<RunFigures>& base,
                                const std::vector<RunFigures>& next, int resamples, uint64_t seed) {
  std::map<std::string, const RunFigures*> by_key;
  for (const RunFigures& r : base) by_key[r.key] = &r;
  std::vector<const RunFigures*> a, b;  // paired: a[i] and b[i] are one walk
  for (const RunFigures& r : next)
    if (const auto it = by_key.find(r.key); it != by_key.end()) {
      a.push_back(it->second);
      b.push_back(&r);
    }
  struct Field {
    const char* name;
    double SuiteFigures::*value;
    const char* unit;
    int digits;
  };
  const std::vector<Field> fields = {
      {"mean error, m", &SuiteFigures::mean_error_m, "", 3},
      {"runs more than 5 m off", &SuiteFigures::runs_over_5m, "", 0},
      {"RELIABLE share", &SuiteFigures::reliable, "%", 3},
      {"RELIABLE within 1 m", &SuiteFigures::precision, "%", 3},
      {"RELIABLE more than 1 m off", &SuiteFigures::false_poses, "", 0},
      {"Brier score of the probability", &SuiteFigures::brier, "", 4},
      {"runs RELIABLE within 1 m 30 s after the first alignment", &SuiteFigures::recovered, "%", 1},
      {"runs never RELIABLE within 1 m", &SuiteFigures::never_recovered, "", 0}};
  const SuiteFigures fa = Figures(a), fb = Figures(b);
  std::vector<std::vector<double>> draws(fields.size());
  SplitMix64 rng(seed);
  std::vector<const RunFigures*> ra(a.size()), rb(b.size());
  for (int k = 0; k < resamples && !a.empty(); ++k) {
    for (size_t i = 0; i < a.size(); ++i) {
      const auto j = static_cast<size_t>(rng.Uniform() * static_cast<double>(a.size()));
      ra[i] = a[std::min(j, a.size() - 1)];
      rb[i] = b[std::min(j, a.size() - 1)];
    }
    const SuiteFigures da = Figures(ra), db = Figures(rb);
    for (size_t f = 0; f < fields.size(); ++f)
      draws[f].push_back(db.*fields[f].value - da.*fields[f].value);
  }
  std::vector<Difference> out;
  for (size_t f = 0; f < fields.size(); ++f) {
    const Field& field = fields[f];
    Difference d{field.name, field.unit, field.digits, fa.*field.value, fb.*field.value};
    std::vector<double>& v = draws[f];
    if (!v.empty()) {
      std::sort(v.begin(), v.end());
      const auto at = [&](double q) {
        return v[std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())))];
      };
      d.low = at(0.025);
      d.high = at(0.975);
    }
    out.push_back(d);
  }
  return out;
}

std::string ReadRuns(const std::string& path, std::vector<RunFigures>* runs) {
  std::ifstream in(path);
  if (!in) return "cannot read " + path;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (line.empty()) continue;
    const nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
    if (j.is_discarded() || !j.is_object() || !j.contains("poses"))
      return path + ":" + std::to_string(n) + ": not a run of eval-suite's results.json";
    RunFigures r;
    r.key = j.value("method", "") + " " + j.value("plan", "") + " " + j.value("scenario", "") +
            " " + std::to_string(j.value("seed", 0));
    r.mean_error_m = j.value("mean_error_m", 0.0);
    r.max_error_m = j.value("max_error_m", 0.0);
    r.scored_poses = j.value("poses", 0.0);
    r.reliable_poses = j.value("reliable_fraction", 0.0) * r.scored_poses;
    r.false_poses = j.value("false_reliable_poses", 0.0);
    r.brier = j.value("brier", 0.0);
    r.time_to_recovered_s = j.value("time_to_recovered_s", -1.0);
    runs->push_back(r);
  }
  return {};
}

}  // namespace floorpose::tools
