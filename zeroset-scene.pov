// clebsch — exported by zeroset
// F = 81*x^3 - 189*x^2*y - 189*x^2*z - 189*x*y^2 + 54*x*y*z - 189*x*z^2 + 81*y^3 - 189*y^2*z - 189*y*z^2 + 81*z^3 - 9*x^2 + 126*x*y + 126*x*z - 9*y^2 + 126*y*z - 9*z^2 - 9*x - 9*y - 9*z + 1
// Render: povray +W800 +H800 +Iscene.pov +Oscene.png
#version 3.7;
global_settings { assumed_gamma 1.0 ambient_light rgb <1, 1, 1> }
background { color rgb <0.73999999999999999, 0.76000000000000001, 0.80000000000000004> }

camera {
  perspective
  location <4.0749775373408825, 2.3526893781254361, 1.7126178082238419>
  sky <-0.29619813272602386, -0.17101007166283433, 0.93969262078590843>
  up <0, 1, 0>
  right <-1, 0, 0>
  angle 84
  look_at <0, 0, 0>
}

light_source { <440.17515629816859, 735.17227267033081, 840.09980104481895> color rgb <0.78000000000000003, 0.76000000000000001, 0.71999999999999997> parallel point_at <0, 0, 0> shadowless }
light_source { <-1038.029796925176, 601.0761501681568, 34.665787679288442> color rgb <0.22, 0.23999999999999999, 0.29999999999999999> parallel point_at <0, 0, 0> shadowless }
light_source { <-104.84449096547029, -1012.3815118744018, 635.68185562434599> color rgb <0.25, 0.25, 0.25> parallel point_at <0, 0, 0> shadowless }

polynomial { 3,
  xyz(0, 0, 0): 1,
  xyz(0, 0, 1): -9,
  xyz(0, 1, 0): -9,
  xyz(1, 0, 0): -9,
  xyz(0, 0, 2): -9,
  xyz(0, 1, 1): 126,
  xyz(0, 2, 0): -9,
  xyz(1, 0, 1): 126,
  xyz(1, 1, 0): 126,
  xyz(2, 0, 0): -9,
  xyz(0, 0, 3): 81,
  xyz(0, 1, 2): -189,
  xyz(0, 2, 1): -189,
  xyz(0, 3, 0): 81,
  xyz(1, 0, 2): -189,
  xyz(1, 1, 1): 54,
  xyz(1, 2, 0): -189,
  xyz(2, 0, 1): -189,
  xyz(2, 1, 0): -189,
  xyz(3, 0, 0): 81
  sturm
  clipped_by {
    sphere { <0, 0, 0>, 1.2000000476837158 }
    sphere { <0, 0, 0>, 1.2000000476837158 }
    plane { <0, 0, 1>, 1.2000000476837158 }
    plane { <0, 0, 1>, 1.2000000476837158 }
  }
  bounded_by { clipped_by }
  texture {
    pigment { color rgb <0.75294119119644165, 0.41960784792900085, 0.28627452254295349> }
    finish { ambient 0.12 diffuse 1 phong 0.35 phong_size 40 }
  }
  interior_texture {
    pigment { color rgb <0.058823529630899429, 0.28627452254295349, 0.3490196168422699> }
    finish { ambient 0.12 diffuse 1 phong 0.35 phong_size 40 }
  }
}
