set terminal pngcairo size 720,420 noenhanced
set output 'fig5_timestep.png'
set xlabel 'dt / T_R'
set ylabel 'angle of repose [deg]'
set key top left
set offsets graph 0.05, graph 0.05, 1, 1
plot 'fig5_timestep_ours.dat' using 1:2:3 with yerrorbars pt 7 title 'ours (slice)'
