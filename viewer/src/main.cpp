#include <ff/viewer/Cli.h>

int main(int argc, char** argv) { return ff::viewer::runCli(argc, argv); }
