set terminal pngcairo size 720,420 noenhanced
set output 'fig7.png'
set xlabel 'd_max [mm]'
set ylabel 'mu_r'
set key top left
set offsets graph 0.05, graph 0.05, 1, 1
plot 'fig7_ours.dat' using 1:2:3 with yerrorbars pt 7 title 'ours (calibrated mu_r, 95% half-width)', 'fig7_paper.dat' using 1:2 with points pt 5 ps 1.5 title 'paper'
