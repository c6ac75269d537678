set terminal pngcairo size 650,720
set output 'comparison.png'
set xlabel 'measured angle, Table 1 [deg]'
set ylabel 'simulated angle [deg]'
set key outside below
set size square
set xrange [32.3:39.2]
set yrange [32.3:39.2]
plot 'comparison_calibration.dat' using 1:2:3 with yerrorbars pt 7 lc rgb '#1f77b4' title 'ours: calibrated (mean +- seed sd)', 'comparison_paper.dat' using 1:2 with points pt 4 ps 1.5 lc rgb '#2ca02c' title 'paper Table 3 (EDEM, one run)', x with lines dt 2 lc rgb 'gray' title 'simulated = measured'
