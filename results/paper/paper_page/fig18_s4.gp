set terminal pngcairo size 900,540 noenhanced
set output 'fig18_s4.png'
set xlabel 'sample mass [kg]'
set ylabel 'angle of repose [deg]'
set key below left Left reverse
set offsets graph 0.05, graph 0.05, graph 0.1, graph 0.1
plot 36.5 with lines dt 2 lw 2 title 'paper: Fig. 18: stabilises at about 36.5 deg (d_max 70 mm)', 'fig18_s4_ours.dat' using 1:2:3 with yerrorbars pt 7 ps 1.5 title 'ours: predicted at mu_r 0.157 (image_flank, mean and seed sd)', 'fig18_s4_calibration.dat' using 1:2:3 with yerrorbars pt 9 ps 1.5 title 'ours: the calibration test, its fit at mu_r (95% half-width)'
