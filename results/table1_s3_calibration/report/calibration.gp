set terminal pngcairo size 700,500
set output '/work/runs/s3/cal/report/calibration.png'
set xlabel 'mu_r'
set ylabel 'angle [deg]'
set key top left
plot '/work/runs/s3/cal/report/calibration.dat' using 1:2 with points pt 7 title 'runs (one per seed)', 36.54 with lines dt 2 title 'target'
