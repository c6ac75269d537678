set terminal pngcairo size 760,560 noenhanced
set output 'fig18_s4.png'
set xlabel 'mu_r (rolling friction)'
set ylabel 'angle of repose [deg]'
set key below maxrows 3
set grid
set offsets graph 0.03, graph 0.03, 1, 1
set object 1 rect from 0.1469, graph 0 to 0.1711, graph 1 behind fc rgb '#dde8f5' fs solid noborder
set arrow 1 from 0.1570, graph 0 to 0.1570, graph 1 nohead dt 3 lw 2 lc rgb '#d62728'
set label 1 'calibrated mu_r 0.157 (95% band)' at 0.1570, graph 0.05 offset 0.5,0 tc rgb '#d62728'
plot 'fig18_s4_fit.dat' using 1:2 with linespoints lw 2 pt 6 lc rgb '#1f77b4' title 'monotone fit', 'fig18_s4_runs.dat' using 1:2 with points pt 7 lc rgb '#333333' title 'runs in the fit (one per seed)', 37.17 with lines dt 2 lc rgb '#2ca02c' title 'target 37.17 deg'
