// A fixture for the no-shell build check: it must be refused, naming this file.
#include <cstdlib>
int plot() { return std::system("gnuplot plot.gp"); }
