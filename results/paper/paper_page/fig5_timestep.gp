set terminal pngcairo size 900,540 noenhanced
set output 'fig5_timestep.png'
set xlabel 'dt / T_R'
set ylabel 'angle of repose [deg]'
set key below left Left reverse
set offsets graph 0.05, graph 0.05, graph 0.1, graph 0.1
plot 22.49 with lines dt 2 lw 2 title 'paper: Fig. 5: 22.49 deg, stable for dt <= 4.84e-6 s (sample 1, mu_r 0.05)', 'fig5_timestep_ours.dat' using 1:2:3 with yerrorbars pt 7 ps 1.5 title 'ours (slice)'
