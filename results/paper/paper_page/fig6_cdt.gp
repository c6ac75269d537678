set terminal pngcairo size 900,540 noenhanced
set output 'fig6_cdt.png'
set xlabel 'mu_r (cdt, EDEM''s)'
set ylabel 'angle of repose [deg]'
set key below left Left reverse
set offsets graph 0.05, graph 0.05, graph 0.1, graph 0.1
plot 'fig6_cdt_paper.dat' using 1:2 with points pt 5 ps 1.5 title 'paper (Fig. 5 text and Table 3 (EDEM, protractor))', 'fig6_cdt_ours.dat' using 1:2:3 with yerrorbars pt 7 ps 1.5 title 'ours (slice)'
