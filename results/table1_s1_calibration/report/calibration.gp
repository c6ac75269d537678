set terminal pngcairo size 700,500
set output '/work/runs/s4/cal_s1/report/calibration.png'
set xlabel 'mu_r'
set ylabel 'angle [deg]'
set key top left
plot '/work/runs/s4/cal_s1/report/calibration.dat' using 1:2 with points pt 7 title 'runs (one per seed)', 33.47 with lines dt 2 title 'target'
