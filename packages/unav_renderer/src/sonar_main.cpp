#include "sonar_node.hpp"

int main(int argc, char** argv) { return unav::run_node<unav::renderer::SonarNode>(argc, argv); }
