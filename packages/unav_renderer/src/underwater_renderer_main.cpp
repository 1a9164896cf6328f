#include "underwater_renderer_node.hpp"

int main(int argc, char** argv) { return unav::run_node<unav::renderer::UnderwaterRendererNode>(argc, argv); }
