set terminal pngcairo size 760,560 noenhanced
set output 't3_s4_epsd.png'
set xlabel 'mu_r (rolling friction)'
set ylabel 'angle of repose [deg]'
set key below maxrows 3
set grid
set offsets graph 0.03, graph 0.03, 1, 1
plot 't3_s4_epsd_fit.dat' using 1:2 with linespoints lw 2 pt 6 lc rgb '#1f77b4' title 'monotone fit', 't3_s4_epsd_runs.dat' using 1:2 with points pt 7 lc rgb '#333333' title 'runs in the fit (one per seed)', 37.17 with lines dt 2 lc rgb '#2ca02c' title 'target 37.17 deg'
