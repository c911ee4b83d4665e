// Written by tools/bench/mid2pov.py from tools/bench/pov/mirror-room.mid; do not edit.
#version 3.7;
global_settings { assumed_gamma 1.0 max_trace_level 6 adc_bailout 1/255 ambient_light 0 }
background { rgb 0 }
// resolution 800 x 600
camera { perspective location <-3.2, -3.4, 1.7> direction <0.565209457, 0.641589113, -0.137483381> right <1.00047866, -0.881374057, -1.85037171e-17> up <0.10494001, 0.119121092, 0.987318469> }
light_source { <-1, -1, 2.6> rgb <39788.7358, 39788.7358, 39788.7358> fade_distance 0.01 fade_power 2 }
light_source { <2, 1.5, 2.6> rgb <28647.8898, 28647.8898, 28647.8898> fade_distance 0.01 fade_power 2 }
object { mesh { triangle { <-4, -4, 0>, <4, -4, 0>, <4, 4, 0> } triangle { <-4, -4, 0>, <4, 4, 0>, <-4, 4, 0> } } texture { pigment { rgb <0.6, 0.55, 0.45> } finish { ambient 0 diffuse 1 } } }  // floor
object { mesh { triangle { <-4, -4, 3>, <-4, 4, 3>, <4, 4, 3> } triangle { <-4, -4, 3>, <4, 4, 3>, <4, -4, 3> } } texture { pigment { rgb <0.8, 0.8, 0.8> } finish { ambient 0 diffuse 1 } } }  // ceiling
object { mesh { triangle { <-4, -4, 0>, <-4, -4, 3>, <4, -4, 3> } triangle { <-4, -4, 0>, <4, -4, 3>, <4, -4, 0> } triangle { <4, -4, 0>, <4, -4, 3>, <4, 4, 3> } triangle { <4, -4, 0>, <4, 4, 3>, <4, 4, 0> } triangle { <4, 4, 0>, <4, 4, 3>, <-4, 4, 3> } triangle { <4, 4, 0>, <-4, 4, 3>, <-4, 4, 0> } triangle { <-4, 4, 0>, <-4, 4, 3>, <-4, -4, 3> } triangle { <-4, 4, 0>, <-4, -4, 3>, <-4, -4, 0> } } texture { pigment { rgb <0.02, 0.02, 0.02> } finish { ambient 0 diffuse 1 phong 4000.8 phong_size 10000 reflection { rgb <0.8, 0.8, 0.8> } } } }  // mirror walls
object { sphere { <0, 0, 0>, 1 } matrix <0.6, 0, 0, 0, 0.6, 0, 0, 0, 0.6, 0.8, 0.6, 0.6> texture { pigment { rgb <0.7, 0.12, 0.1> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // ball
object { torus { 0.55, 0.2 matrix <1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 0, 0> } matrix <1, 0, 0, 0, 0, 1, 0, -1, 0, -0.8, 1.6, 0.75> texture { pigment { rgb <0.45, 0.32, 0.08> } finish { ambient 0 diffuse 1 phong 30.5 phong_size 120 reflection { rgb <0.5, 0.4, 0.15> } } } }  // ring
object { cone { <0, 0, -1>, 1, <0, 0, 1>, 0 } matrix <0.45, 0, 0, 0, 0.45, 0, 0, 0, 0.8, 2.2, -0.6, 0.8> texture { pigment { rgb <0.12, 0.2, 0.65> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // cone
object { intersection { plane { <0, 0, 1>, 1 } plane { <0, 0, -1>, 1 } plane { <0.5, 0.866025404, 0>, 0.5 } plane { <-1, 3.84592537e-16, 0>, 0.5 } plane { <0.5, -0.866025404, 0>, 0.5 } bounded_by { box { <-1, -1, -1>, <1, 1, 1> } } } matrix <0.482962913, 0.129409523, 0, -0.129409523, 0.482962913, 0, 0, 0, 0.35, -1.6, -0.4, 0.35> texture { pigment { rgb <0.45, 0.32, 0.08> } finish { ambient 0 diffuse 1 phong 30.5 phong_size 120 reflection { rgb <0.5, 0.4, 0.15> } } } }  // triangle
difference {  // holed cube
  object { box { <-1, -1, -1>, <1, 1, 1> } matrix <0.36861842, 0.258109396, 0, -0.258109396, 0.36861842, 0, 0, 0, 0.45, 1.6, 2.4, 0.45> texture { pigment { rgb <0.12, 0.2, 0.65> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0.221171052, 0.154865638, 0, -0.154865638, 0.221171052, 0, 0, 0, 0.675, 1.6, 2.4, 0.45> texture { pigment { rgb <0.12, 0.2, 0.65> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
  object { cylinder { <0, 0, -1>, <0, 0, 1>, 1 } matrix <0.221171052, 0.154865638, 0, 0, 0, 0.27, 0.387164095, -0.55292763, 0, 1.6, 2.4, 0.45> texture { pigment { rgb <0.12, 0.2, 0.65> } finish { ambient 0 diffuse 1 phong 4.65 phong_size 60 reflection { rgb <0.15, 0.15, 0.15> } } } }  // 
}
