;;;; Benchmark of cram-native against the raw C++ program tests/bench/native/raw_bench.cpp
;;;; (the same operations written directly on Bullet), measured in the same run.

(require :asdf)
(require :sb-posix)
(asdf:load-system "cram-native")

(defpackage :cram-native-bench (:use :cl :cram-native))
(in-package :cram-native-bench)

(defparameter *native-dir* (asdf:system-relative-pathname "cram-native" "projection/native/"))
(defparameter *pr2-urdf* #p"/work/shared/models/pr2_description/urdf/pr2.urdf")

(defun chain-urdf (n)
  "URDF of a chain of N revolute joints (axes alternating z and y) with box links, the robot
of raw_bench.cpp."
  (with-output-to-string (s)
    (format s "<robot name='chain'><link name='l0'/>")
    (loop for j from 1 to n
          do (format s "<link name='l~d'><collision><geometry><box size='0.04 0.04 0.08'/></geometry></collision></link>
<joint name='j~d' type='revolute'><parent link='l~d'/><child link='l~d'/><origin xyz='0 0 ~a'/><axis xyz='~a'/><limit lower='-3' upper='3' effort='1' velocity='1'/></joint>"
                     j j (1- j) j (if (= j 1) "0.05" "0.08") (if (oddp j) "0 0 1" "0 1 0")))
    (format s "</robot>")))

(defun build-scene ()
  "Plane, 33 boxes and the 45-joint chain robot (as in raw_bench.cpp)."
  (let ((w (make-world)) (boxes '()))
    (add-plane w)
    (dotimes (i 33)
      (push (add-box w (list (+ 1 (* 0.3 (mod i 6))) (- (* 0.3 (floor i 6)) 0.8)
                             (+ 0.05 (* 0.12 (mod i 3))) 0 0 0 1)
                     '(0.1 0.1 0.1) :mass 1)
            boxes))
    (values w (add-urdf w (chain-urdf 45)) (reverse boxes))))

(defun raw-times ()
  "Alist (name . seconds) from the raw C++ program, or NIL when it cannot be built or run."
  (ignore-errors
   (uiop:run-program (list "make" "-s" "-C" (namestring *native-dir*) "bench")
                     :output nil :error-output nil)
   (let ((out (cram-bench:run-peer (namestring (merge-pathnames "build/raw_bench" *native-dir*)))))
     (when out
       (with-input-from-string (s out)
         (loop for line = (read-line s nil) while line
               collect (let ((sp (position #\Space line)))
                         (cons (subseq line 0 sp)
                               (let ((*read-default-float-format* 'double-float))
                                 (coerce (read-from-string (subseq line (1+ sp))) 'double-float))))))))))

(defun row (measure ours raw-name raw &key (goal-ratio 1.2d0) goal-abs)
  (let* ((peer (cdr (assoc raw-name raw :test #'string=)))
         (ratio (and peer (/ ours peer))))
    (cram-bench:add-row measure (cram-bench:format-seconds ours)
                        :peer-name (and peer "raw C++ Bullet") :peer (and peer (cram-bench:format-seconds peer))
                        :ratio ratio
                        :goal (cond (goal-abs (format nil "<= ~a" (cram-bench:format-seconds goal-abs)))
                                    (goal-ratio (format nil "<= ~,1fx raw" goal-ratio)))
                        :met (cond (goal-abs (<= ours goal-abs))
                                   (ratio (<= ratio goal-ratio))
                                   (t :unknown)))))

(cram-bench:define-benchmark native ()
  (let ((raw (raw-times)))
    (multiple-value-bind (w r boxes) (build-scene)
      (unwind-protect
           (let* ((b (nth 5 boxes))
                  (pose (make-array 7 :element-type 'double-float :initial-contents '(1d0 0d0 1d0 0d0 0d0 0d0 1d0)))
                  (joints (make-array 45 :element-type '(signed-byte 32)))
                  (values (make-array 45 :element-type 'double-float))
                  (poses (make-array (* 7 46) :element-type 'double-float))
                  (i 0))
             (dotimes (k 45) (setf (aref joints k) k))
             (row "native: teleport a body"
                  (cram-bench:time-per-call
                   (lambda () (setf (aref pose 0) (+ 1d0 (* 1d-6 (mod (incf i) 100))))
                     (set-object-pose w b pose)))
                  "teleport" raw)
             (set-object-pose w b '(1.6 -0.8 0.05 0 0 0 1))
             (row "native: set 45 joints + read link poses"
                  (cram-bench:time-per-call
                   (lambda () (incf i)
                     (dotimes (k 45) (setf (aref values k) (* 0.01d0 (mod (+ i k) 20))))
                     (set-robot-joints w r joints values)
                     (robot-link-poses w r poses)))
                  "joints-and-poses" raw)
             (row "native: robot vs world collision check"
                  (cram-bench:time-per-call (lambda () (object-contacts w r)))
                  "robot-collision" raw)
             (row "native: copy world (34 bodies + 45-link robot)"
                  (cram-bench:time-per-call (lambda () (destroy-world (copy-world w))))
                  "copy" raw :goal-ratio nil :goal-abs 1d-3)
             (row "native: simulate 1 s, 34 bodies, 240 Hz"
                  (cram-bench:median-seconds
                   (lambda ()
                     (with-world (s)
                       (add-plane s)
                       (dotimes (k 33)
                         (add-box s (list (* 0.3 (mod k 6)) (* 0.3 (floor k 6)) (+ 0.3 (* 0.12 (mod k 3))) 0 0 0 1)
                                  '(0.1 0.1 0.1) :mass 1))
                       (simulate s 1 (/ 1d0 240))))
                   :runs 5)
                  "simulate" raw)
             (let ((cam (look-at '(0 0 1.2) (subseq (object-pose w b) 0 3))))
               (row "native: visibility query (128x96)"
                    (cram-bench:time-per-call (lambda () (visibility w cam b)))
                    "visibility" raw :goal-ratio nil :goal-abs 1d-3)
               (let ((png (format nil "/tmp/cram-native-bench-~d.png" (sb-posix:getpid))))
                 (row "native: render 320x240 PNG"
                      (cram-bench:time-per-call (lambda () (render-png w cam png :width 320 :height 240))
                                                :runs 3)
                      "png" raw :goal-ratio nil)
                 (ignore-errors (delete-file png)))))
        (destroy-world w)))
    (when (probe-file *pr2-urdf*)
      (add-search-dir "/work/shared/models")
      (with-world (w)
        (let* ((r (add-urdf w (uiop:read-file-string *pr2-urdf*)))
               (c (make-chain w r "torso_lift_link" "r_wrist_roll_link"))
               (state (sb-ext:seed-random-state 7))
               (n 300) (solved 0) (total 0d0))
          (multiple-value-bind (lo hi) (chain-limits c)
            (dotimes (k n)
              (let* ((q (map '(simple-array double-float (*))
                             (lambda (a b) (+ a (random (- b a) state))) lo hi))
                     (target (chain-fk c q))
                     (t0 (get-internal-real-time))
                     (sol (chain-ik c target :random-seed (1+ k))))
                (incf total (/ (- (get-internal-real-time) t0) (float internal-time-units-per-second 1d0)))
                (when sol (incf solved)))))
          (destroy-chain c)
          (cram-bench:add-row "native: PR2 right arm IK (mean, random reachable poses)"
                              (format nil "~a, ~,1f% solved" (cram-bench:format-seconds (/ total n))
                                      (* 100 (/ solved n)))
                              :goal "<= 300 µs, >= 99%"
                              :met (and (<= (/ total n) 300d-6) (>= (/ solved n) 0.99))))))))
