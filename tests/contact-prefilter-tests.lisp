;;;; The contact queries of an articulated object leave out, without Bullet's contact query, the
;;;; link pairs a GJK distance proves apart (cram-native:set-contact-prefilter): their answers
;;;; are those of the queries that ask Bullet about every pair.

(in-package :cram-plans-tests.sweep)

(in-suite sweep)

(defun random-pose-near (x y radius state)
  "A base pose within RADIUS of (X Y), turned at random."
  (let ((yaw (- (random (* 2 pi) state) pi)))
    (cl-transforms:make-pose
     (cl-transforms:make-3d-vector (+ x (- (random (* 2 radius) state) radius))
                                   (+ y (- (random (* 2 radius) state) radius)) 0)
     (cl-transforms:axis-angle->quaternion (cl-transforms:make-3d-vector 0 0 1) yaw))))

(test contact-queries-answer-as-without-the-gjk-prefilter
  ;; the PR2 at seeded poses between the kitchen's table and counters, its right arm anywhere:
  ;; contacts (touching, and within 2 cm) and first contacts, with and without the prefilter
  (with-open-world (:kitchen t)
    (let* ((w (btr:world-handle btr:*current-bullet-world*)) (r (btr:object-handle (robot)))
           (floor (btr:object-handle (btr:object btr:*current-bullet-world* :floor)))
           (state (sb-ext:seed-random-state 31)) (touching 0) (differ '()))
      (unwind-protect
           (dotimes (k 150)
             (setf (btr:pose (robot)) (random-pose-near -1.5d0 -0.2d0 0.6d0 state))
             (set-right-arm (random-arm state))
             (dolist (threshold '(0d0 0.02d0))
               (flet ((answers ()
                        (list (cram-native:object-contacts w r :threshold threshold :except (list floor))
                              (cram-native:object-first-contact w r :threshold threshold
                                                                    :except (list floor)))))
                 (cram-native:set-contact-prefilter nil)
                 (let ((asked (answers)))
                   (cram-native:set-contact-prefilter t)
                   (let ((filtered (answers)))
                     (when (first asked) (incf touching))
                     (unless (equalp asked filtered)
                       (push (list k threshold asked filtered) differ)))))))
        (cram-native:set-contact-prefilter t))
      (is (null differ) "~d answers differ, e.g. ~s" (length differ) (first differ))
      ;; the poses put the robot into the furniture often enough to test something
      (is (> touching 40) "only ~d of 300 queries found contacts" touching))))
