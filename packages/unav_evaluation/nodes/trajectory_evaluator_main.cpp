#include "trajectory_evaluator.hpp"

int main(int argc, char** argv) { return unav::run_node<unav_evaluation::TrajectoryEvaluator>(argc, argv); }
