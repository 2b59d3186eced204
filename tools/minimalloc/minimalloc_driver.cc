// Minimal driver for google/minimalloc's solver (timing on the challenging traces, docs/memory.md).
// Build: see build.sh beside this file. Usage: minimalloc_driver TRACE.csv CAPACITY
#include <chrono>
#include <fstream>
#include <iostream>
#include <sstream>
#include "solver.h"
#include "validator.h"
int main(int argc, char** argv) {
  std::ifstream ifs(argv[1]);
  std::string line;
  std::getline(ifs, line);
  minimalloc::Problem problem;
  while (std::getline(ifs, line)) {
    if (line.empty()) continue;
    std::stringstream ss(line); std::string f[4];
    for (int k = 0; k < 4; ++k) std::getline(ss, f[k], ',');
    minimalloc::Buffer b; b.id = f[0];
    b.lifespan = {std::stoll(f[1]), std::stoll(f[2])}; b.size = std::stoll(f[3]);
    problem.buffers.push_back(b);
  }
  problem.capacity = std::stoll(argv[2]);
  minimalloc::SolverParams params;
  if (argc > 3) params.minimize_capacity = true;
  minimalloc::Solver solver(params);
  auto t0 = std::chrono::steady_clock::now();
  auto solution = solver.Solve(problem);
  auto t1 = std::chrono::steady_clock::now();
  double s = std::chrono::duration<double>(t1 - t0).count();
  if (!solution.ok()) { std::cout << argv[1] << " capacity " << argv[2] << " status " << solution.status() << " seconds " << s << " backtracks " << solver.get_backtracks() << "\n"; return 0; }
  auto v = minimalloc::Validate(problem, *solution);
  std::cout << argv[1] << " capacity " << argv[2] << " height " << solution->height << " seconds " << s << " backtracks " << solver.get_backtracks() << " valid " << (v == minimalloc::ValidationResult::kGood) << "\n";
  return 0;
}
