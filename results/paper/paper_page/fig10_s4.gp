set terminal pngcairo size 900,540 noenhanced
set output 'fig10_s4.png'
set xlabel 'W / d_max (d_max 8 mm)'
set ylabel 'angle of repose [deg]'
set key below left Left reverse
set offsets graph 0.05, graph 0.05, graph 0.1, graph 0.1
plot 'fig10_s4_paper.dat' using 1:2 with points pt 5 ps 1.5 title 'paper (sec. 3: W 10 mm, W/d_max 1.25: particles lodge in the funnel, angle 0)', 'fig10_s4_ours.dat' using 1:2:3 with yerrorbars pt 7 ps 1.5 title 'ours: predicted at mu_r 0.157 (image_flank, mean and seed sd)', 'fig10_s4_nopile.dat' using 1:2:3 with yerrorbars pt 6 ps 1.5 title 'ours: no pile in any seed (drawn at angle 0)', 'fig10_s4_calibration.dat' using 1:2:3 with yerrorbars pt 9 ps 1.5 title 'ours: the calibration test, its fit at mu_r (95% half-width)'
