;;;; Tests of BTR:*ALL-MESHES-AS-COMPOUND* and the :COMPOUND key of :mesh and :urdf objects: one
;;;; convex hull per part of a mesh file keeps its hollows, one hull over all of it fills them.
;;;; The meshes (OBJ files of several objects) are written to a temporary directory.

(in-package :cram-btr-api-tests)
(in-suite btr-api)

;;; ---- meshes of several parts -------------------------------------------------------------

(defun obj-box (lo hi)
  "The part (vertices faces) of an axis-aligned box from corner LO to corner HI."
  (destructuring-bind ((x0 y0 z0) (x1 y1 z1)) (list lo hi)
    (list (loop for i below 8
                collect (list (if (logbitp 0 i) x1 x0) (if (logbitp 1 i) y1 y0) (if (logbitp 2 i) z1 z0)))
          '((0 2 3 1) (4 5 7 6) (0 1 5 4) (2 6 7 3) (0 4 6 2) (1 3 7 5)))))

(defun write-obj (path parts)
  "Write PARTS, each (vertices faces) with faces as 0-based vertex indices, to the OBJ file PATH
as one object per part. Returns PATH."
  (with-open-file (s path :direction :output :if-exists :supersede)
    (let ((offset 1))
      (loop for (vertices faces) in parts for k from 0
            do (format s "o part~d~%" k)
               (dolist (v vertices) (format s "v ~{~,6f~^ ~}~%" v))
               (dolist (f faces) (format s "f ~{~d~^ ~}~%" (mapcar (lambda (i) (+ i offset)) f)))
               (incf offset (length vertices)))))
  path)

(defun mesh-test-file (name)
  "A path for the mesh file NAME in this process's temporary directory."
  (let ((dir (format nil "/tmp/cram-btr-compound-~d/" (sb-posix:getpid))))
    (ensure-directories-exist dir)
    (concatenate 'string dir name)))

(defun tray-obj ()
  "A square tray 0.3 m wide as five parts: a bottom 0.02 m thick and four walls 0.1 m high; its
origin is the middle of its underside."
  (write-obj (mesh-test-file "tray.obj")
             (list (obj-box '(-0.15 -0.15 0) '(0.15 0.15 0.02))
                   (obj-box '(-0.15 -0.15 0) '(-0.13 0.15 0.1))
                   (obj-box '(0.13 -0.15 0) '(0.15 0.15 0.1))
                   (obj-box '(-0.13 -0.15 0) '(0.13 -0.13 0.1))
                   (obj-box '(-0.13 0.13 0) '(0.13 0.15 0.1)))))

(defparameter *plate-sides* 16 "Corners of the polygons the plate is made of.")

(defun plate-obj ()
  "A plate of 32 parts: a flat foot (radius 0.07 m, 0.012 m thick) of 16 wedges and 16 flat
slabs of the rim, each 0.01 m thick (vertically) and rising at 25 degrees from the foot's edge
to radius 0.12 m (0.033 m above the underside). The rim of an identical plate put on it clears
its rim as soon as the feet touch, so plates nest. Origin: the middle of the underside. (Parts
of at most 64 triangle corners are kept as exact hulls by the shim.)"
  (let* ((n *plate-sides*) (foot-r 0.07d0) (foot-h 0.012d0) (rim-r 0.12d0) (rim-t 0.01d0)
         (rise (* (- rim-r foot-r) (tan (* 25 (/ pi 180)))))
         (corners (loop for i below n for a = (/ (* 2 pi i) n) collect (cons (cos a) (sin a)))))
    (flet ((at (c r z) (list (* r (car c)) (* r (cdr c)) z)))
      (write-obj
       (mesh-test-file "plate.obj")
       (loop for i below n
             for c0 = (nth i corners) for c1 = (nth (mod (1+ i) n) corners)
             collect (list (list '(0 0 0) (at c0 foot-r 0) (at c1 foot-r 0)
                                 (list 0 0 foot-h) (at c0 foot-r foot-h) (at c1 foot-r foot-h))
                           '((0 2 1) (3 4 5) (0 1 4 3) (1 2 5 4) (2 0 3 5)))
             collect (list (list (at c0 foot-r 0) (at c1 foot-r 0)
                                 (at c1 rim-r rise) (at c0 rim-r rise)
                                 (at c0 foot-r rim-t) (at c1 foot-r rim-t)
                                 (at c1 rim-r (+ rise rim-t)) (at c0 rim-r (+ rise rim-t)))
                           '((0 3 2 1) (4 5 6 7) (0 1 5 4) (1 2 6 5) (2 3 7 6) (3 0 4 7))))))))

;;; ---- helpers -------------------------------------------------------------------------------

(defun floor-world ()
  "A new current world with a floor."
  (let ((w (make-instance 'btr:bt-reasoning-world)))
    (setf btr:*current-bullet-world* w)
    (btr:add-object w :static-plane :floor '((0 0 0) (0 0 0 1)))
    w))

(defun height-of (world name)
  (cl-transforms:z (cl-transforms:origin (btr:pose (btr:object world name)))))

(defun distance-from-z-axis (world name)
  (let ((o (cl-transforms:origin (btr:pose (btr:object world name)))))
    (sqrt (+ (expt (cl-transforms:x o) 2) (expt (cl-transforms:y o) 2)))))

(defun drop-cube-into-tray (&rest tray-keys)
  "The height at which a 0.06 m cube dropped over the middle of a tray (made with TRAY-KEYS and
standing on the floor) comes to rest."
  (let ((w (floor-world)))
    (apply #'btr:add-object w :mesh 'tray '((0 0 0) (0 0 0 1)) :mesh (tray-obj) tray-keys)
    (btr:add-object w :box 'cube '((0 0 0.3) (0 0 0 1)) :size '(0.06 0.06 0.06) :mass 0.1)
    (btr:simulate w 3)
    (height-of w 'cube)))

;;; On the bottom of the tray the cube's centre is at 0.02 + 0.03 m; on top of the tray's hull
;;; at 0.1 + 0.03 m.
(defun inside-tray-p (z) (< (abs (- z 0.05d0)) 5d-3))
(defun on-tray-hull-p (z) (< (abs (- z 0.13d0)) 5d-3))

;;; ---- :mesh objects ------------------------------------------------------------------------

(test all-meshes-as-compound-is-t-and-documented
  (is (eq t btr:*all-meshes-as-compound*))
  (is (eq :external (nth-value 1 (find-symbol "*ALL-MESHES-AS-COMPOUND*" :btr))))
  (is (search "convex hull" (documentation 'btr:*all-meshes-as-compound* 'variable))))

(test mesh-compound-keeps-the-hollow
  "A cube dropped into a movable tray rests on its bottom when the tray is a compound of its
parts, and on top of it when the tray is one convex hull."
  (let ((z (drop-cube-into-tray :mass 1 :compound t)))
    (is (inside-tray-p z) "the cube rests at ~,4f m, not in the compound tray" z))
  (let ((z (drop-cube-into-tray :mass 1 :compound nil)))
    (is (on-tray-hull-p z) "the cube rests at ~,4f m, not on the hull of the tray" z)))

(test mesh-compound-of-static-meshes
  "A static tray is its exact mesh when compound and one hull when not."
  (is (inside-tray-p (drop-cube-into-tray :compound t)))
  (is (on-tray-hull-p (drop-cube-into-tray :compound nil))))

(test mesh-compound-defaults-to-the-variable
  "Without :compound the tray follows *ALL-MESHES-AS-COMPOUND* at the time it is made; an
explicit :compound wins over it."
  (is (inside-tray-p (drop-cube-into-tray :mass 1)))
  (let ((btr:*all-meshes-as-compound* nil))
    (is (on-tray-hull-p (drop-cube-into-tray :mass 1)))
    (is (inside-tray-p (drop-cube-into-tray :mass 1 :compound t))))
  (let ((btr:*all-meshes-as-compound* t))
    (is (on-tray-hull-p (drop-cube-into-tray :mass 1 :compound nil)))))

(defun pile-of-plates (compound &key (count 5))
  "Heights of COUNT plates put one after the other 0.035 m above the top plate of a pile in the
middle of the floor (a plate is 0.033 m high), from the bottom one up, and the largest distance
of one from the pile's axis. The plates are the mesh keyword :TEST-PLATE spawned while
*ALL-MESHES-AS-COMPOUND* is COMPOUND."
  (let ((btr:*mesh-files* (cons (list :test-plate (plate-obj) nil) btr:*mesh-files*))
        (btr:*all-meshes-as-compound* compound)
        (w (floor-world))
        (names (loop for i below count collect (intern (format nil "PLATE-~d" i) :keyword)))
        (top 0))
    (dolist (name names)
      (force-ll (prolog `(and (btr:bullet-world ?w)
                              (assert (btr:object ?w :mesh ,name ((0 0 ,(+ top 0.035)) (0 0 0 1))
                                                  :mass 0.2 :mesh :test-plate :color (1 0 0)))
                              (btr:simulate ?w 1))))
      (setf top (height-of w name)))
    (btr:simulate w 2)
    (values (mapcar (lambda (n) (height-of w n)) names)
            (reduce #'max names :key (lambda (n) (distance-from-z-axis w n))))))

(test pile-of-plates-stays-stacked-as-compound
  "As in CRAM's pile-of-plates: plates made of parts nest, each lying in the one below it (0.014
m higher: the foot and the margins), and stay on the pile; plates that are one hull each lie on
top of each other (0.035 m higher), and their pile is higher."
  (multiple-value-bind (heights off-axis) (pile-of-plates t)
    (let ((steps (mapcar #'- (rest heights) heights)))
      (is (< (abs (first heights)) 3d-3) "the bottom plate is at ~,4f m" (first heights))
      (is (every (lambda (s) (< 0.01d0 s 0.02d0)) steps)
          "the plates do not nest: heights ~{~,4f~^ ~}" heights)
      (is (< off-axis 1d-2) "a plate has slid ~,4f m off the pile" off-axis)
      (multiple-value-bind (hull-heights hull-off-axis) (pile-of-plates nil)
        (is (every (lambda (s) (< 0.03d0 s 0.04d0)) (mapcar #'- (rest hull-heights) hull-heights))
            "the plates as hulls do not lie on each other: heights ~{~,4f~^ ~}" hull-heights)
        (is (< hull-off-axis 1d-2) "a plate as a hull has slid ~,4f m off the pile" hull-off-axis)
        (is (< (car (last heights)) (- (car (last hull-heights)) 0.05d0))
            "the compound pile (top ~,4f m) is not lower than the hull pile (top ~,4f m)"
            (car (last heights)) (car (last hull-heights)))))))

;;; ---- :urdf objects ------------------------------------------------------------------------

(defun tray-robot-urdf ()
  (format nil "<robot name='tray_robot'><link name='tray'><collision><geometry><mesh filename='~a'/></geometry></collision></link></robot>"
          (tray-obj)))

(defun cube-in-tray-touches-p (&rest robot-keys)
  "Does a movable 0.06 m cube in the middle of the tray of an articulated object made with
ROBOT-KEYS touch it?"
  (let ((w (floor-world)))
    (apply #'btr:add-object w :urdf 'tray-robot '((0 0 0) (0 0 0 1)) :urdf (tray-robot-urdf) robot-keys)
    (btr:add-object w :box 'cube '((0 0 0.06) (0 0 0 1)) :size '(0.06 0.06 0.06) :mass 0.1)
    (btr:objects-in-contact-p w 'cube 'tray-robot)))

(test urdf-compound-as-in-cram
  "A URDF link mesh is one convex hull by default (CRAM's robot objects), one hull per part
with :compound t, and the exact mesh in a static environment whatever :compound says; the
variable for mesh objects does not change it."
  (is (cube-in-tray-touches-p))
  (is (cube-in-tray-touches-p :compound nil))
  (is (not (cube-in-tray-touches-p :compound t)))
  (let ((btr:*all-meshes-as-compound* t))
    (is (cube-in-tray-touches-p)))
  (is (not (cube-in-tray-touches-p :collision-group :static-filter)))
  (is (not (cube-in-tray-touches-p :collision-group :static-filter :compound nil))))

(test project-robots-have-no-collision-meshes
  "The PR2 and Pepper of this project collide with boxes, cylinders and spheres only, so :compound
does not change them (their setups pass :compound t for robot URDFs with meshes)."
  (dolist (file '("robots/pr2/pr2.urdf" "robots/pepper/pepper.urdf"))
    (let ((model (cl-urdf:parse-urdf (uiop:read-file-string
                                      (asdf:system-relative-pathname "cram-plans/cram-bullet-reasoning" file))))
          (kinds '()))
      (loop for link being the hash-values of (cl-urdf:links model)
            do (dolist (c (cl-urdf:collision link))
                 (pushnew (first (getf c :geometry)) kinds)))
      (is (subsetp kinds '(:box :cylinder :sphere)) "~a collides with ~s" file kinds)
      (is (member :box kinds)))))
