;;;; Tests of the projection clocks and of special projection variables.

(defpackage :cram-projection-clock-tests
  (:use :cl :fiveam))

(in-package :cram-projection-clock-tests)

(def-suite projection-clocks :in cram-plans-tests:all
  :description "LINEAR-CLOCK, PARTIALLY-ORDERED-CLOCK, special projection variables.")
(in-suite projection-clocks)

(test linear-clock-adds-up-waits
  (let ((clock (make-instance 'proj:linear-clock)))
    (is (= 0 (proj:clock-time clock)))
    (let ((start (get-internal-real-time)))
      (proj:clock-wait clock 100)
      (is (< (- (get-internal-real-time) start) (* 0.5 internal-time-units-per-second))
          "no real waiting"))
    (proj:clock-wait clock 2.5)
    (is (= 102.5 (proj:clock-time clock)))
    (signals error (proj:clock-wait clock -1))
    (signals error (proj:clock-wait clock "soon"))
    (signals simple-error (proj:clock-wait :not-a-clock 1))
    (signals simple-error (proj:clock-time 42))))

(test partially-ordered-clock-overlaps-parallel-waits
  ;; as on a robot, and with the ordered starts of projection (a clock wait lets the next
  ;; branch start)
  (dolist (ordered '(nil t))
    (let ((clock (make-instance 'proj:partially-ordered-clock :increment-delay 0.05))
          (cpl:*ordered-concurrency* ordered)
          end-1 end-2)
      (cpl:top-level
        (cpl:par
          (progn (proj:clock-wait clock 5) (setf end-1 (proj:clock-time clock)))
          (progn (proj:clock-wait clock 10) (setf end-2 (proj:clock-time clock)))))
      (is (<= 5 end-1 9.99) "the shorter wait ends first: ~a" end-1)
      (is (= 10 end-2))
      (is (= 10 (proj:clock-time clock)) "parallel waits overlap: 10, not 15 (ordered ~a)" ordered))))

(test disabled-partially-ordered-clock-does-not-step
  (dolist (ordered '(nil t))
    (let ((clock (make-instance 'proj:partially-ordered-clock :increment-delay 0.02))
          (cpl:*ordered-concurrency* ordered)
          real-end-of-wait real-end-of-disabled)
      (cpl:top-level
        (cpl:par
          (progn (proj:clock-wait clock 3) (setf real-end-of-wait (get-internal-real-time)))
          (proj:with-partially-ordered-clock-disabled clock
            (sleep 0.2)
            (setf real-end-of-disabled (get-internal-real-time)))))
      (is (>= real-end-of-wait real-end-of-disabled))
      (is-true (proj:partially-ordered-clock-enabled clock)))))

(defvar *projection-test-counter* :global)

(proj:define-special-projection-variable *projection-test-counter* (list 0))

(proj:define-projection-environment projection-clock-test-environment)

(test special-projection-variables-are-bound-afresh
  (let (first second inner)
    (proj:with-projection-environment projection-clock-test-environment
      (setf first *projection-test-counter*)
      (incf (car *projection-test-counter*))
      (cpl:top-level (setf inner *projection-test-counter*)))
    (proj:with-projection-environment projection-clock-test-environment
      (setf second *projection-test-counter*))
    (is (equal '(1) first))
    (is (eq first inner) "plan tasks see the binding")
    (is (equal '(0) second) "each environment evaluates the value form again")
    (is (eq :global *projection-test-counter*))))
