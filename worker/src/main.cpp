#include "csgtile/worker/cli.h"

int main(int argc, char** argv) { return csgtile::worker::run_cli(argc, argv); }
