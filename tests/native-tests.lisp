;;;; Tests of cram-native: the shim through its Lisp binding.

(defpackage :cram-native-tests
  (:use :cl :fiveam :cram-native)
  (:export #:native))

(in-package :cram-native-tests)

(def-suite native :in cram-plans-tests:all :description "The C shim and its CFFI binding.")
(in-suite native)

(defun approx (a b &optional (eps 1d-6)) (< (abs (- a b)) eps))

(defun nan ()
  "A quiet double-float NaN."
  (sb-kernel:make-double-float -524288 0))

(defmacro signals-naming ((&rest substrings) &body body)
  "Assert BODY signals a NATIVE-ERROR whose message contains every one of SUBSTRINGS."
  `(let ((c (handler-case (progn ,@body nil) (native-error (e) e))))
     (is (typep c 'native-error) "expected a native-error from ~s" ',body)
     (when c
       (dolist (s (list ,@substrings))
         (is (search s (native-error-message c)) "message ~s does not name ~s"
             (native-error-message c) s)))))

(test end-to-end-drop-box
  "A 0.2 m box dropped from z=2 onto a plane rests at z=0.1 after 3 s at 240 Hz."
  (with-world (w)
    (add-plane w)
    (let ((box (add-box w '(0 0 2 0 0 0 1) '(0.2 0.2 0.2) :mass 1)))
      (is (= 720 (simulate w 3 (/ 1d0 240))))
      (let ((p (object-pose w box)))
        (is (approx (aref p 2) 0.1d0 2d-3))
        (is (< (abs (aref p 0)) 0.5d0))
        (is (< (reduce #'max (body-velocity w box) :key #'abs) 1d-2))))))

(defparameter *arm-urdf* "<robot name=\"arm\">
  <material name=\"red\"><color rgba=\"1 0 0 1\"/></material>
  <link name=\"base\"><collision><geometry><box size=\"0.2 0.2 0.1\"/></geometry></collision></link>
  <link name=\"upper\">
    <visual><origin xyz=\"0 0 0.25\"/><geometry><cylinder radius=\"0.05\" length=\"0.5\"/></geometry><material name=\"red\"/></visual>
    <collision><origin xyz=\"0 0 0.25\"/><geometry><cylinder radius=\"0.05\" length=\"0.5\"/></geometry></collision></link>
  <link name=\"lower\"><collision><origin xyz=\"0.2 0 0\"/><geometry><box size=\"0.4 0.05 0.05\"/></geometry></collision></link>
  <link name=\"tool\"/>
  <link name=\"finger\"><collision><geometry><sphere radius=\"0.02\"/></geometry></collision></link>
  <joint name=\"j1\" type=\"revolute\"><parent link=\"base\"/><child link=\"upper\"/><origin xyz=\"0 0 0.05\"/><axis xyz=\"0 0 1\"/><limit lower=\"-3\" upper=\"3\" effort=\"1\" velocity=\"1\"/></joint>
  <joint name=\"j2\" type=\"revolute\"><parent link=\"upper\"/><child link=\"lower\"/><origin xyz=\"0 0 0.5\"/><axis xyz=\"0 1 0\"/><limit lower=\"-2\" upper=\"2\" effort=\"1\" velocity=\"1\"/></joint>
  <joint name=\"j3\" type=\"fixed\"><parent link=\"lower\"/><child link=\"tool\"/><origin xyz=\"0.4 0 0\"/></joint>
  <joint name=\"slide\" type=\"prismatic\"><parent link=\"tool\"/><child link=\"finger\"/><axis xyz=\"1 0 0\"/><limit lower=\"0\" upper=\"0.1\" effort=\"1\" velocity=\"1\"/><mimic joint=\"j2\" multiplier=\"0.5\" offset=\"0.01\"/></joint>
</robot>" "A 2-DOF arm with a fixed tool frame and a mimic prismatic finger.")

(defun finger-position (a b &optional (base '(0 0 0)))
  "Hand-computed position of the arm's finger for joints j1 = A, j2 = B."
  (let ((r (+ 0.41d0 (* 0.5d0 b))))
    (list (+ (first base) (* (cos a) r (cos b)))
          (+ (second base) (* (sin a) r (cos b)))
          (+ (third base) 0.55d0 (- (* r (sin b)))))))

(test handle-validation
  (let ((w (make-world)))
    (let ((b (add-box w '(0 0 1 0 0 0 1) '(0.1 0.1 0.1) :mass 1)))
      (signals-naming ("component 2" "NaN") (set-object-pose w b (list 0 0 (nan) 0 0 0 1)))
      (signals-naming ("infinity" "component 0") (set-object-pose w b (list sb-ext:double-float-positive-infinity 0 0 0 0 0 1)))
      (signals-naming ("999" "not a live object") (object-pose w 999))
      (signals-naming ("box size x" "-1") (add-box w '(0 0 0 0 0 0 1) '(-1 1 1)))
      (signals-naming ("mass") (add-sphere w '(0 0 0 0 0 0 1) 0.1 :mass -2))
      (signals-naming ("zero quaternion") (set-object-pose w b '(0 0 0 0 0 0 0)))
      (signals-naming ("pose") (set-object-pose w b '(1 2 3)))
      (let ((other (make-world)))
        (signals-naming ((format nil "handle ~d" b)) (object-pose other b))
        (destroy-world other))
      (destroy-world w)
      (signals-naming ((format nil "world handle ~d is not a live world" w)) (object-pose w b))
      (is (not (world-alive-p w)))
      (let ((c (handler-case (add-plane w) (native-error (e) e))))
        (is (typep c 'native-error))
        (is (= -1 (native-error-code c)))
        (is (equal "cn_body_add_plane" (native-error-function c)))))))

(test copy-independence
  (with-world (w)
    (add-plane w)
    (let* ((b (add-box w '(0 0 1 0 0 0 1) '(0.2 0.2 0.2) :mass 1))
           (s (add-sphere w '(1 0 0.5 0 0 0 1) 0.1))
           (r (add-urdf w *arm-urdf* :pose '(2 0 0 0 0 0 1)))
           (c (copy-world w)))
      (unwind-protect
           (progn
             (set-robot-joints w r '(0 1) '(0.5 0.3))
             (is (= (world-object-count w) (world-object-count c)))
             (is (equalp (object-pose w b) (object-pose c b)))
             (is (equalp (object-pose w s) (object-pose c s)))
             (set-object-pose c b '(5 5 5 0 0 0 1))
             (is (approx 1d0 (aref (object-pose w b) 2)))
             (is (approx 5d0 (aref (object-pose c b) 2)))
             (is (approx 0d0 (aref (robot-joints c r) 0)))
             (is (approx 0.5d0 (aref (robot-joints w r) 0)))
             (simulate c 1)
             (is (approx 1d0 (aref (object-pose w b) 2)))
             (is (< (aref (object-pose c b) 2) 5d0))
             ;; a copy of a copy after simulation matches its source
             (let ((c2 (copy-world w)))
               (simulate w 0.5) (simulate c2 0.5)
               (is (approx (aref (object-pose w b) 2) (aref (object-pose c2 b) 2) 1d-9))
               (destroy-world c2)))
        (destroy-world c)))))

(test urdf-links-joints-fk
  (with-world (w)
    (let ((r (add-urdf w *arm-urdf* :pose '(1 2 0 0 0 0 1))))
      (is (equal "arm" (robot-name w r)))
      (is (= 5 (robot-link-count w r)))
      (is (= 4 (robot-joint-count w r)))
      (is (equal "base" (robot-link-name w r (robot-root-link w r))))
      (is (equal '("j1" "j2" "j3" "slide") (robot-joint-names w r)))
      (let ((info (robot-joint-info w r (robot-joint-index w r "slide"))))
        (is (eq :prismatic (getf info :type)))
        (is (eql (robot-joint-index w r "j2") (getf info :mimic)))
        (is (approx 0.5d0 (getf info :multiplier))))
      (is (eq :revolute (getf (robot-joint-info w r 1) :type)))
      (is (approx 2d0 (getf (robot-joint-info w r 1) :upper)))
      (is (not (robot-link-has-body-p w r (robot-link-index w r "tool"))))
      (is (robot-link-has-body-p w r (robot-link-index w r "finger")))
      (signals-naming ("unknown link 'foo'" (format nil "robot ~d" r)) (robot-link-index w r "foo"))
      (signals-naming ("unknown joint 'bar'") (robot-joint-index w r "bar"))
      (loop for (a b) in '((0d0 0d0) (0.7d0 -0.4d0) (-1.2d0 1.1d0))
            do (set-robot-joints w r (list (robot-joint-index w r "j1") (robot-joint-index w r "j2"))
                                 (list a b))
               (let ((p (robot-link-pose w r (robot-link-index w r "finger")))
                     (e (finger-position a b '(1 2 0))))
                 (is (every (lambda (x y) (approx x y 1d-9)) (subseq p 0 3) e)))
               (is (approx (+ 0.01d0 (* 0.5d0 b)) (aref (robot-joints w r) 3) 1d-12)))
      ;; all link poses in one call agree with single-link queries
      (let ((all (robot-link-poses w r)))
        (is (= 35 (length all)))
        (is (equalp (subseq all 28 35) (robot-link-pose w r 4))))
      ;; base pose moves everything
      (set-object-pose w r '(0 0 1 0 0 0 1))
      (is (approx 1.55d0 (aref (robot-link-pose w r (robot-link-index w r "lower")) 2) 1d-9))
      (signals-naming ("joint index 17") (set-robot-joints w r '(17) '(0.1)))
      (signals-naming ("j1" "NaN") (set-robot-joints w r '(0) (list (nan)))))))

(test urdf-errors
  (with-world (w)
    (signals-naming ("malformed URDF") (add-urdf w "<robot name='x'><link name='a'/><joint name='j' type='revolute'><parent link='a'/><child link='zz'/></joint></robot>"))
    (signals-naming ("malformed URDF") (add-urdf w "this is not xml"))
    (signals-naming ("nopkg_here")
      (add-urdf w "<robot name='m'><link name='a'><collision><geometry><mesh filename='package://nopkg_here/does-not-exist.stl'/></geometry></collision></link></robot>"))
    (is (zerop (world-object-count w)))))

(defun temp-dir ()
  (let ((d (format nil "/tmp/cram-native-test-~d/" (sb-posix:getpid))))
    (ensure-directories-exist d)
    d))

(defun write-cube-obj (path &optional (half 0.05))
  (with-open-file (s path :direction :output :if-exists :supersede)
    (loop for (x y z) in '((-1 -1 -1) (1 -1 -1) (1 1 -1) (-1 1 -1) (-1 -1 1) (1 -1 1) (1 1 1) (-1 1 1))
          do (format s "v ~f ~f ~f~%" (* half x) (* half y) (* half z)))
    (format s "f 1 3 2~%f 1 4 3~%f 5 6 7~%f 5 7 8~%f 1 2 6~%f 1 6 5~%f 2 3 7~%f 2 7 6~%f 3 4 8~%f 3 8 7~%f 4 1 5~%f 4 5 8~%"))
  path)

(defun write-tetra-stl (path)
  (with-open-file (s path :direction :output :if-exists :supersede)
    (format s "solid t~%")
    (loop for tri in '(((0 0 0) (0.1 0 0) (0 0.1 0)) ((0 0 0) (0 0 0.1) (0.1 0 0))
                       ((0 0 0) (0 0.1 0) (0 0 0.1)) ((0.1 0 0) (0 0 0.1) (0 0.1 0)))
          do (format s "facet normal 0 0 0~%outer loop~%~{vertex ~{~f ~f ~f~}~%~}endloop~%endfacet~%" tri))
    (format s "endsolid t~%"))
  path)

(test mesh-loading
  (let* ((dir (temp-dir))
         (obj (write-cube-obj (concatenate 'string dir "cube.obj")))
         (stl (write-tetra-stl (concatenate 'string dir "tetra.stl")))
         (bad (concatenate 'string dir "corrupt.stl")))
    (with-open-file (s bad :direction :output :if-exists :supersede) (write-string "solid x garbage 1 2" s))
    (with-world (w)
      (add-plane w)
      (let ((m (add-mesh w '(0 0 1 0 0 0 1) obj :mass 1))
            (st (add-mesh w '(1 0 0 0 0 0 1) stl :scale 2)))
        (is (eq :mesh (body-shape w m)))
        (simulate w 2)
        (is (approx 0.05d0 (aref (object-pose w m) 2) 3d-3))
        ;; static STL scaled by 2: AABB reaches 0.2
        (is (approx 0.2d0 (aref (object-aabb w st) 5) 3d-3))
        ;; a second load of the same file and scale gives the same dimensions (cached)
        (let ((m2 (add-mesh w '(3 0 1 0 0 0 1) obj :mass 1)))
          (is (approx (- (aref (object-aabb w m2) 5) (aref (object-aabb w m2) 2))
                      (- (aref (object-aabb w m) 5) (aref (object-aabb w m) 2)) 1d-6))))
      (signals-naming ("missing-file.stl") (add-mesh w '(0 0 0 0 0 0 1) (concatenate 'string dir "missing-file.stl")))
      (signals-naming ("corrupt.stl") (add-mesh w '(0 0 0 0 0 0 1) bad :mass 1))
      ;; URDF mesh through a registered package
      (add-package-path "cn_test_pkg" dir)
      (let ((r (add-urdf w "<robot name='m'><link name='a'><collision><origin xyz='0 0 0.5'/><geometry><mesh filename='package://cn_test_pkg/cube.obj' scale='2 2 2'/></geometry></collision></link></robot>")))
        (is (approx 0.6d0 (aref (object-aabb w r 0) 5) 3d-3)))
      (signals-naming ("corrupt.stl" "link 'a'")
        (add-urdf w "<robot name='m'><link name='a'><collision><geometry><mesh filename='package://cn_test_pkg/corrupt.stl'/></geometry></collision></link></robot>")))))

(test link-aabbs-are-each-links-own
  "OBJECT-AABB of one link of an articulated object is the box of that link's body alone (the
finger's sphere where the finger is), of a link without a body its frame's origin; the links'
boxes together make the whole object's box."
  (with-world (w)
    (let ((r (add-urdf w *arm-urdf* :pose '(1 2 0 0 0 0 1))))
      (set-robot-joints w r (list (robot-joint-index w r "j1") (robot-joint-index w r "j2"))
                        '(0.7d0 -0.4d0))
      (let* ((finger (robot-link-index w r "finger"))
             (tool (robot-link-index w r "tool"))
             (box (object-aabb w r finger))
             (centre (subseq (robot-link-pose w r finger) 0 3)))
        (loop for k below 3
              do (is (approx (- (elt centre k) 0.02d0) (aref box k) 1d-6))
                 (is (approx (+ (elt centre k) 0.02d0) (aref box (+ k 3)) 1d-6)))
        (is (equalp (object-aabb w r tool)
                    (let ((o (subseq (robot-link-pose w r tool) 0 3))) (concatenate 'vector o o))))
        (let ((whole (object-aabb w r))
              (boxes (loop for l below (robot-link-count w r)
                           when (robot-link-has-body-p w r l) collect (object-aabb w r l))))
          (loop for k below 3
                do (is (= (aref whole k) (reduce #'min boxes :key (lambda (b) (aref b k)))))
                   (is (= (aref whole (+ k 3)) (reduce #'max boxes :key (lambda (b) (aref b (+ k 3))))))))))))

(test physics-sees-teleported-static-bodies
  "A static box teleported under a falling box between simulations holds it up there, and
teleported away lets it fall on: the physics works with the boxes where the bodies are now."
  (with-world (w)
    (let ((table (add-box w '(5 0 0 0 0 0 1) '(1 1 0.2)))
          (box (add-box w '(0 0 0.5 0 0 0 1) '(0.2 0.2 0.2) :mass 1)))
      (simulate w 0.05)
      (set-object-pose w table '(0 0 0 0 0 0 1))
      (simulate w 1)
      (is (approx 0.2d0 (aref (object-pose w box) 2) 5d-3))
      (set-object-pose w table '(5 0 0 0 0 0 1))
      (simulate w 0.5)
      (is (< (aref (object-pose w box) 2) -0.5d0)))))

(test robot-link-colors-are-each-links-colour
  "ROBOT-LINK-COLORS gives, 4 per link, what OBJECT-COLOR gives link by link: a link's own
colour once set, else its visual's colour, else grey."
  (with-world (w)
    (let ((r (add-urdf w *arm-urdf*)))
      (set-object-color w r '(0 0.5 1) (robot-link-index w r "lower"))
      (let ((all (robot-link-colors w r)))
        (is (= (* 4 (robot-link-count w r)) (length all)))
        (dotimes (l (robot-link-count w r))
          (is (equalp (object-color w r l) (subseq all (* 4 l) (* 4 (1+ l))))))
        (is (equalp #(1d0 0d0 0d0 1d0) (subseq all (* 4 (robot-link-index w r "upper"))
                                            (* 4 (1+ (robot-link-index w r "upper"))))))
        (is (equalp #(0d0 0.5d0 1d0 1d0) (subseq all (* 4 (robot-link-index w r "lower"))
                                              (* 4 (1+ (robot-link-index w r "lower"))))))
        (is (equalp #(0.5d0 0.5d0 0.5d0 1d0) (subseq all (* 4 (robot-link-index w r "base"))
                                                  (* 4 (1+ (robot-link-index w r "base"))))))))
    (signals-naming ("rigid body") (robot-link-colors w (add-box w '(0 0 0 0 0 0 1) '(1 1 1))))))

(test robot-link-aabbs-are-each-links-box
  "ROBOT-LINK-AABBS gives, 6 per link, what OBJECT-AABB gives link by link: a link's body's box,
or its origin for a link without a body."
  (with-world (w)
    (let ((r (add-urdf w *arm-urdf* :pose '(1 2 0 0 0 0.3 0.95))))
      (set-robot-joints w r (list (robot-joint-index w r "j1")) '(0.4d0))
      (let ((all (robot-link-aabbs w r)))
        (is (= (* 6 (robot-link-count w r)) (length all)))
        (dotimes (l (robot-link-count w r))
          (is (equalp (object-aabb w r l) (subseq all (* 6 l) (* 6 (1+ l))))))
        (let ((k (* 6 (robot-link-index w r "tool"))))
          (is (equalp (subseq all k (+ k 3)) (subseq all (+ k 3) (+ k 6))) "a point: no body"))
        (let ((k (* 6 (robot-link-index w r "base"))))
          (is (< (aref all k) 1d0 (aref all (+ k 3))) "the base's box holds its origin"))))
    (signals-naming ("rigid body") (robot-link-aabbs w (add-box w '(0 0 0 0 0 0 1) '(1 1 1))))))

(test link-poses-if-are-the-poses-after-setting-the-joints
  "ROBOT-LINK-POSES-IF gives the poses the links would have with some joints set (a mimic
joint following its leader), digit for digit the poses after setting them, and leaves the
world as it was."
  (with-world (w)
    (let* ((r (add-urdf w *arm-urdf* :pose '(1 2 0 0 0 0.3 0.95)))
           (j1 (robot-joint-index w r "j1")) (j2 (robot-joint-index w r "j2"))
           (links (list (robot-link-index w r "finger") (robot-link-index w r "upper")
                        (robot-link-index w r "base")))
           (before (robot-link-poses w r)))
      (set-robot-joints w r (list j1) '(0.4d0))
      (let ((start (copy-seq (robot-link-poses w r)))
            (what-if (robot-link-poses-if w r (list j1 j2) '(0.4d0 -0.7d0) links)))
        (is (equalp start (robot-link-poses w r)))
        (is (equalp #(0.4d0 0d0) (subseq (robot-joints w r) 0 2)))
        (set-robot-joints w r (list j2) '(-0.7d0))
        (is (equalp what-if (concatenate 'vector (loop for l in links
                                                       append (coerce (robot-link-pose w r l) 'list)))))
        (is (not (equalp before (robot-link-poses w r)))))
      (signals-naming ("joint index 17") (robot-link-poses-if w r '(17) '(0.1) links))
      (signals-naming ("link index 99") (robot-link-poses-if w r (list j1) '(0.1) '(99)))
      (signals-naming ("j1" "NaN") (robot-link-poses-if w r (list j1) (list (nan)) links)))))

(test link-poses-after-many-moves-are-those-of-a-robot-placed-there-at-once
  "However a robot got to its base pose and joint values (base moves, some joints set, values
set again that it had before, -0 and 0), its link poses are digit for digit those of a new robot
of the same model given that base pose and those values at once."
  (with-world (w)
    (let* ((pose '(1 2 0 0 0 0.3 0.95))
           (r (add-urdf w *arm-urdf* :pose pose))
           (n (length (robot-joints w r)))
           (all (loop for j below n collect j))
           (state (sb-ext:seed-random-state 11))
           (differing 0))
      (dotimes (i 300)
        (case (random 3 state)
          (0 (let ((half-turn (random 1d0 state)))
               (setf pose (list (random 2d0 state) (random 2d0 state) 0 0 0
                                (sin half-turn) (cos half-turn)))
               (set-object-pose w r pose)))
          (1 (let ((j (random n state)))
               (set-robot-joints w r (list j) (list (nth (random 4 state) '(0.4d0 -0.7d0 0d0 -0d0))))))
          (t (set-robot-joints w r all (loop repeat n collect (- (random 2d0 state) 1d0)))))
        ;; the new robot is given the same base pose as the robot's last (as it was written)
        (let ((fresh (add-urdf w *arm-urdf* :pose pose)))
          (set-robot-joints w fresh all (coerce (robot-joints w r) 'list))
          (unless (equalp (robot-link-poses w r) (robot-link-poses w fresh))
            (incf differing))
          (remove-object w fresh)))
      (is (= 0 differing) "~d of 300 states differ from a fresh robot's" differing))))

(test urdf-with-moved-joint-origins
  ;; the object of a URDF with some joints' <origin> attributes changed, made from the model of
  ;; the original text: the link poses of the edited text, bit for bit, in any joint state
  (with-world (w)
    (let* ((moved '(("j2" "0.01 -0.02 0.47" "0.1 -0.2 0.3") ("j3" "0.35 0.0 0.01" "0 0 1.5707963")))
           (edited (let ((text *arm-urdf*))
                     (loop for (from to) in '(("<origin xyz=\"0 0 0.5\"/>"
                                               "<origin xyz=\"0.01 -0.02 0.47\" rpy=\"0.1 -0.2 0.3\"/>")
                                              ("<origin xyz=\"0.4 0 0\"/>"
                                               "<origin xyz=\"0.35 0.0 0.01\" rpy=\"0 0 1.5707963\"/>"))
                           do (let ((at (search from text)))
                                (setf text (concatenate 'string (subseq text 0 at) to
                                                        (subseq text (+ at (length from)))))))
                     text))
           (a (add-urdf w edited :pose '(1 2 0 0 0 0 1)))
           (b (add-urdf w *arm-urdf* :pose '(1 2 0 0 0 0 1) :moved-joints moved))
           (plain (add-urdf w *arm-urdf* :pose '(1 2 0 0 0 0 1))))
      (is (equalp (robot-link-poses w a) (robot-link-poses w b)))
      (is (not (equalp (robot-link-poses w a) (robot-link-poses w plain))))
      (dolist (r (list a b))
        (set-robot-joints w r (list (robot-joint-index w r "j1") (robot-joint-index w r "j2"))
                          '(0.7d0 -0.4d0)))
      (is (equalp (robot-link-poses w a) (robot-link-poses w b)))
      (is (equal (robot-joint-names w a) (robot-joint-names w b)))
      ;; the original model is not changed
      (is (equalp (robot-link-poses w plain)
                  (robot-link-poses w (add-urdf w *arm-urdf* :pose '(1 2 0 0 0 0 1)))))
      (signals-naming ("no joint 'nope'" "arm") (add-urdf w *arm-urdf* :moved-joints '(("nope" "0 0 0" "0 0 0"))))
      (signals-naming ("j2" "origin" "1 2") (add-urdf w *arm-urdf* :moved-joints '(("j2" "1 2" "0 0 0"))))
      (signals-naming (":moved-joints") (add-urdf w *arm-urdf* :moved-joints '(("j2" 1 2)))))))
