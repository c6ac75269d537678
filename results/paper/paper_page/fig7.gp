set terminal pngcairo size 900,540 noenhanced
set output 'fig7.png'
set xlabel 'd_max [mm]'
set ylabel 'mu_r'
set key below left Left reverse
set offsets graph 0.05, graph 0.05, graph 0.1, graph 0.1
plot 'fig7_paper.dat' using 1:2 with points pt 5 ps 1.5 title 'paper (Table 3 / Fig. 7 (EDEM''s convention))', 'fig7_cdt.dat' using 1:2:3 with yerrorbars pt 7 ps 1.5 title 'ours, cdt (calibrated mu_r, 95% half-width)', 'fig7_epsd.dat' using 1:2:3 with yerrorbars pt 7 ps 1.5 title 'ours, epsd (calibrated mu_r, 95% half-width)'
