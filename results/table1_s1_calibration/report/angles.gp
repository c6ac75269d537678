set terminal pngcairo size 900,520 noenhanced
set output 'angles.png'
set ylabel 'angle of repose [deg]'
set xtics rotate by 30 right
set key outside top center horizontal
set grid ytics
set offsets 0.5,0.5,2,2
plot 'angles.dat' using 1:2:3:xtic(6) with yerrorbars pt 7 title 'image atan(2H/D) (vision on renders)', '' using ($1+0.1):4:5 with yerrorbars pt 5 title 'particles atan(2H/D)', '' using ($1+0.2):7:8 with yerrorbars pt 9 title 'image flank angle (vision on renders)'
