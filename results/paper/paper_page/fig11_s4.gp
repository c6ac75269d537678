set terminal pngcairo size 900,540 noenhanced
set output 'fig11_s4.png'
set xlabel 'd_max [mm]'
set ylabel 'angle of repose [deg]'
set key below left Left reverse
set offsets graph 0.05, graph 0.05, graph 0.1, graph 0.1
set xrange [0:9]
plot 36.2 with lines dt 2 lw 2 title 'paper: Figs. 11-13: revised tests at d_max 2-8 mm, about 36.2 to 36.8 deg', 36.8 with lines dt 2 lw 2 title '', 'fig11_s4_ours.dat' using 1:2:3 with yerrorbars pt 7 ps 1.5 title 'ours: predicted at mu_r 0.157 (image_flank, mean and seed sd)', 'fig11_s4_calibration.dat' using 1:2:3 with yerrorbars pt 9 ps 1.5 title 'ours: the calibration test, its fit at mu_r (95% half-width)'
