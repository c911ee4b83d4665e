// Written by tools/bench/mid2pov.py from tools/bench/pov/classic.mid; do not edit.
#version 3.7;
global_settings { assumed_gamma 1.0 max_trace_level 6 adc_bailout 1/255 ambient_light 0 }
background { rgb 0 }
// resolution 800 x 600
camera { perspective location <0, -10, 4> direction <0, 1.31905745, -0.383725803> right <1.33333333, -0, 0> up <0, 0.279329541, 0.960195297> }
light_source { <-6, -7, 9> rgb <350140.875, 350140.875, 350140.875> fade_distance 0.01 fade_power 2 }
light_source { <7, -4, 5> rgb <111408.46, 111408.46, 111408.46> fade_distance 0.01 fade_power 2 }
object { mesh { triangle { <-40, -30, 0>, <40, -30, 0>, <40, 60, 0> } triangle { <-40, -30, 0>, <40, 60, 0>, <-40, 60, 0> } } texture { pigment { rgb <0.6, 0.6, 0.55> } finish { ambient 0 diffuse 1 } } }  // ground
object { sphere { <0, 0, 0>, 1 } matrix <0.9, 0, 0, 0, 0.9, 0, 0, 0, 0.9, -2.8, 0, 0.9> texture { pigment { rgb <0.7, 0.12, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // sphere
object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.606217783, 0.35, 0, -0.35, 0.606217783, 0, 0, 0, 0.7, -0.4, -1.2, 0.7> texture { pigment { rgb <0.12, 0.2, 0.65> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // box
object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0.5, 0, 0, 0, 0.5, 0, 0, 0, 1.1, 1.8, -0.6, 1.1> texture { pigment { rgb <0.15, 0.55, 0.2> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // cylinder
object { cone { <0, 0, -1>, 1, <0, 0, 1>, 0 } matrix <0.7, 0, 0, 0, 0.7, 0, 0, 0, 1, 3.8, 1.2, 1> texture { pigment { rgb <0.7, 0.6, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // cone
object { torus { 0.8, 0.25 matrix <1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 0, 0> } matrix <1, 0, 0, 0, 0.939692621, 0.342020143, 0, -0.342020143, 0.939692621, -1, 2.6, 0.9> texture { pigment { rgb <0.75, 0.35, 0.08> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // torus
object { prism { linear_sweep linear_spline -1, 1, 9, <1, 0>, <0.3, 0.3>, <0, 1>, <-0.3, 0.3>, <-1, 0>, <-0.3, -0.3>, <0, -1>, <0.3, -0.3>, <1, 0> matrix <1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 0, 0> } matrix <0.689365427, 0.121553724, 0, -0.121553724, 0.689365427, 0, 0, 0, 0.5, 1.2, 2.4, 0.5> texture { pigment { rgb <0.75, 0.75, 0.75> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // prism
difference {  // difference
  object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.543784672, -0.253570957, 0, 0.253570957, 0.543784672, 0, 0, 0, 0.6, -4.2, 3.2, 0.6> texture { pigment { rgb <0.12, 0.2, 0.65> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  object { sphere { <0, 0, 0>, 1 } matrix <0.67973084, -0.316963696, 0, 0.316963696, 0.67973084, 0, 0, 0, 0.75, -4.2, 3.2, 0.6> texture { pigment { rgb <0.12, 0.2, 0.65> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
}
intersection {  // intersection
  object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.563815572, 0.205212086, 0, -0.205212086, 0.563815572, 0, 0, 0, 0.6, 4, 4, 0.6> texture { pigment { rgb <0.7, 0.12, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  object { sphere { <0, 0, 0>, 1 } matrix <0.761151023, 0.277036316, 0, -0.277036316, 0.761151023, 0, 0, 0, 0.81, 4, 4, 0.6> texture { pigment { rgb <0.7, 0.12, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
}
