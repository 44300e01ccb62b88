;;;; cram-native: headless rendering, PNG output and visibility queries.

(in-package :cram-native)

(defcn "cn_render" :int (w :int) (cam :pointer) (conv :int) (fov :double) (width :int)
  (height :int) (near :double) (far :double) (rgb :pointer) (depth :pointer) (seg :pointer))
(defcn "cn_render_png" :int (w :int) (cam :pointer) (conv :int) (fov :double) (width :int)
  (height :int) (path :string))
(defcn "cn_write_png" :int (path :string) (rgb :pointer) (width :int) (height :int))
(defcn "cn_look_at" :int (eye :pointer) (target :pointer) (up :pointer) (conv :int) (out :pointer))
(defcn "cn_visibility_above" :int (w :int) (cam :pointer) (conv :int) (fov :double) (width :int)
  (height :int) (o :int) (l :int) (min-z :double) (frac :pointer) (occ :pointer) (cap :int))

(defun %convention (c function)
  (case c
    (:optical 0)
    (:forward 1)
    (t (arg-error function "camera convention ~s, expected :optical (z forward, x right, y down) or :forward (x forward, z up)" c))))

(defun %image-size (width height function)
  (unless (and (typep width '(integer 1 8192)) (typep height '(integer 1 8192)))
    (arg-error function "image size ~s x ~s, expected integers in 1..8192" width height)))

(defun render (world camera-pose &key (convention :optical) (fov 50) (width 320) (height 240)
                                      (near 0.05) (far 50) (rgb t) depth segmentation)
  "Render WORLD from CAMERA-POSE (vertical FOV in degrees).  Returns three values: an RGB
byte vector (3 per pixel, rows top to bottom) when RGB, a DVEC of depths in metres along the
view axis (0 = nothing) when DEPTH, and an (signed-byte 32) vector of (object link) per pixel
(-1 -1 = background) when SEGMENTATION."
  (%image-size width height 'render)
  (let* ((n (* width height))
         (rgb-v (and rgb (make-array (* 3 n) :element-type '(unsigned-byte 8))))
         (depth-v (and depth (make-dvec n)))
         (seg-v (and segmentation (make-array (* 2 n) :element-type '(signed-byte 32))))
         (spare-b (make-array 1 :element-type '(unsigned-byte 8)))
         (spare-d (make-dvec 1))
         (spare-i (make-array 1 :element-type '(signed-byte 32))))
    (with-pose-pointer (pc camera-pose 'render)
      (with-vector-pointers ((pr (or rgb-v spare-b)) (pd (or depth-v spare-d))
                             (ps (or seg-v spare-i)))
        (ccall "cn_render" world pc (%convention convention 'render)
               (real-arg fov 'render "fov") width height (real-arg near 'render "near")
               (real-arg far 'render "far")
               (if rgb-v pr (cffi:null-pointer)) (if depth-v pd (cffi:null-pointer))
               (if seg-v ps (cffi:null-pointer)))))
    (values rgb-v depth-v seg-v)))

(defun render-png (world camera-pose path &key (convention :optical) (fov 50) (width 320)
                                               (height 240))
  "Render WORLD from CAMERA-POSE into the PNG file PATH; return PATH."
  (%image-size width height 'render-png)
  (with-pose-pointer (pc camera-pose 'render-png)
    (ccall "cn_render_png" world pc (%convention convention 'render-png)
           (real-arg fov 'render-png "fov") width height (path-arg path 'render-png "PNG path")))
  path)

(defun write-png (path rgb width height)
  "Write the RGB byte vector (3 per pixel, rows top to bottom) as a PNG file PATH."
  (%image-size width height 'write-png)
  (unless (and (typep rgb '(simple-array (unsigned-byte 8) (*))) (= (length rgb) (* 3 width height)))
    (arg-error 'write-png "RGB data must be a byte vector of ~d elements" (* 3 width height)))
  (with-vector-pointers ((p rgb))
    (ccall "cn_write_png" (path-arg path 'write-png "PNG path") p width height))
  path)

(defun look-at (eye target &key (up '(0 0 1)) (convention :optical))
  "Camera pose (DVEC of 7) at EYE looking at TARGET with UP roughly up."
  (let ((e (to-dvec eye 3 'look-at "eye")) (g (to-dvec target 3 'look-at "target"))
        (u (to-dvec up 3 'look-at "up")) (out (make-dvec 7)))
    (with-vector-pointers ((pe e) (pg g) (pu u) (po out))
      (ccall "cn_look_at" pe pg pu (%convention convention 'look-at) po))
    out))

(defun visibility (world camera-pose object &key (link -1) (convention :optical) (fov 50)
                                                 (width 128) (height 96) min-z)
  "Fraction of OBJECT (or one LINK) visible from CAMERA-POSE: its pixels in the scene divided
by its pixels when rendered alone with the camera turned towards it; with MIN-Z (metres), only
the parts of OBJECT above that height count.  Second value: list of the occluding object
handles."
  (%image-size width height 'visibility)
  (let ((frac (make-dvec 1))
        (occ (make-array 64 :element-type '(signed-byte 32)))
        (min-z (if min-z (real-arg min-z 'visibility "min-z") sb-ext:double-float-negative-infinity)))
    (let ((n (with-pose-pointer (pc camera-pose 'visibility)
               (with-vector-pointers ((pf frac) (po occ))
                 (ccall "cn_visibility_above" world pc (%convention convention 'visibility)
                        (real-arg fov 'visibility "fov") width height object link min-z pf po 64)))))
      (values (aref frac 0) (coerce (subseq occ 0 (min n 64)) 'list)))))
