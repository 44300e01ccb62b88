;;;; IK benchmark: 1 000 random reachable poses per PR2 arm (forward kinematics of random joint
;;;; configurations within the limits), each solved from a random seed configuration. Ours
;;;; (URDF-PROJ:SOLVE-IK: the native damped least-squares chain solver with seeded restarts, then the Lisp
;;;; Levenberg–Marquardt solver) against the bare native call in the same run, printed
;;;; beside PyBullet's figures from the anchors (≈ 55 µs for 20 iterations leaving a 5 cm error,
;;;; ≈ 270 µs to sub-millimetre).

(require :asdf)
(asdf:load-asd (merge-pathnames "../../cram-plans.asd" *load-truename*))
(handler-bind ((warning #'muffle-warning))
  (asdf:load-system "cram-plans/cram-urdf-projection")
  (asdf:load-system "cram-plans/cram-pr2-description"))

(defpackage :cram-bench.ik
  (:use :cl :cram-bench))

(in-package :cram-bench.ik)

(defparameter *poses-per-arm* 1000 "Random reachable poses per arm.")

(defun make-pr2-world ()
  "A world with only the PR2 (IK needs its chains)."
  (rob-int:set-robot-name :pr2)
  (let ((w (make-instance 'btr:bt-reasoning-world)))
    (btr:add-object w :urdf :pr2 '((0 0 0) (0 0 0 1))
                    :urdf (uiop:read-file-string (asdf:system-relative-pathname "cram-plans/cram-urdf-projection" "robots/pr2/pr2.urdf")))
    w))

(defun cases (chain n seed)
  "N (goal seed-configuration) pairs for CHAIN from a random state seeded with SEED."
  (let ((state (sb-ext:seed-random-state seed)))
    (loop repeat n
          collect (list (urdf-proj:chain-forward-kinematics chain (urdf-proj::random-configuration chain state))
                        (urdf-proj::random-configuration chain state)))))

(defun run-cases (cases solve)
  "Call SOLVE on each case; return (solved mean-seconds)."
  (let ((solved 0) (start (now-seconds)))
    (dolist (c cases)
      (when (funcall solve (first c) (second c)) (incf solved)))
    (list solved (/ (- (now-seconds) start) (length cases)))))

(defun warm-up (chain arm)
  "Solve 200 other cases for CHAIN with ours and the bare native call: the first calls in a
fresh image are slower, and neither side is measured cold."
  (let ((warm (cases chain 200 (if (eq arm :left) 303 404))))
    (let ((urdf-proj:*ik-random-state* (sb-ext:seed-random-state 9)))
      (run-cases warm (lambda (goal seed) (urdf-proj:solve-ik chain goal :seed seed))))
    (run-cases warm (lambda (goal seed)
                      (cram-native:chain-ik (urdf-proj::ik-chain-native chain)
                                            (btr::pose->vector goal) :seed seed :max-restarts 30)))))

(define-benchmark ik ()
  (let* ((btr:*current-bullet-world* (make-pr2-world))
         (robot (btr:get-robot-object)))
    (dolist (arm '(:left :right))
      (let* ((chain (urdf-proj:arm-ik-chain arm robot))
             (cases (cases chain *poses-per-arm* (if (eq arm :left) 101 202)))
             (ours (let ((urdf-proj:*ik-random-state* (sb-ext:seed-random-state 7)))
                     (warm-up chain arm)
                     (run-cases cases (lambda (goal seed)
                                        (urdf-proj:solve-ik chain goal :seed seed)))))
             (native (let ((n 0))
                       (run-cases cases (lambda (goal seed)
                                          (cram-native:chain-ik (urdf-proj::ik-chain-native chain)
                                                                (btr::pose->vector goal)
                                                                :seed seed :max-restarts 30
                                                                :random-seed (incf n))))))
             (rate (/ (first ours) (float (length cases)))))
        (add-row (format nil "PR2 ~(~a~) arm IK, ~d random reachable poses (1 mm / 0.01 rad): ~
                              solved ~,1f % (bare native solver ~,1f %)"
                         arm (length cases) (* 100 rate)
                         (* 100 (/ (first native) (float (length cases)))))
                 (format-seconds (second ours))
                 :peer-name "bare native chain-ik call, 30 restarts"
                 :peer (format-seconds (second native))
                 :ratio (/ (second ours) (second native))
                 :goal "≥ 99 %, ≤ 300 µs mean (PyBullet: ≈ 55 µs / 20 it. at 5 cm, ≈ 270 µs sub-mm)"
                 :met (and (>= rate 0.99) (<= (second ours) 300d-6)))))))
