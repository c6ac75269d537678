set terminal pngcairo size 640,420
set output 'residual_lift_speed_m_s.png'
set xlabel 'lift_speed_m_s' noenhanced
set ylabel 'measured - predicted angle [deg]'
set key outside top center horizontal noenhanced
set grid
set offsets graph 0.05, graph 0.05, graph 0.05, graph 0.05
set xzeroaxis lt -1
plot 'residual_lift_speed_m_s.dat' index 0 u ($1):2:4 w yerrorbars pt 7 lc rgb '#c0392b' t 'before', '' index 0 u ($1):3:4 w yerrorbars pt 5 lc rgb '#2471a3' t 'after'
