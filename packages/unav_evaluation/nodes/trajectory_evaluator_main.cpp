#include "trajectory_evaluator.hpp"

int main(int argc, char** argv) { return unav::run_node<unav::evaluation::TrajectoryEvaluator>(argc, argv); }
