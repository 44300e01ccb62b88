;;;; The browser viewer costs projection nothing while no page is open: move-bottle with the
;;;; viewer loaded and serving (no page) and runs being recorded, against no recording and no
;;;; viewer.

(defpackage :cram-bench.viewer
  (:use :cl :cram-bench))

(in-package :cram-bench.viewer)

(load-tool "demo.lisp" :cram-plans-demo)
(handler-bind ((warning #'muffle-warning))
  (asdf:load-system "cram-plans/viewer"))

(defun median-of (values)
  (nth (floor (length values) 2) (sort (copy-list values) #'<)))

(define-benchmark viewer-idle ()
  ;; the runs alternate between the two settings (the machine's speed drifts over seconds);
  ;; starting and stopping the viewer is not timed
  (let ((withouts '()) (withs '()))
    (dotimes (i 63)
      (let ((without (let ((cram-viewer:*record-runs* nil)
                           (cram-viewer:*start-viewer-from-debug-window* nil))
                       (cram-viewer:stop-viewer)
                       (move-bottle-seconds)))
            (with (progn (btr:viewer :port 0 :stream nil)
                         (move-bottle-seconds))))
        (when (>= i 3) (push without withouts) (push with withs))))
    (cram-viewer:stop-viewer)
    (let ((with (median-of withs)) (without (median-of withouts)))
      (add-row "move-bottle with the viewer serving (no page open) and the run recorded, warm median (runs alternating with the peer's)"
               (format-seconds with)
               :peer-name "the same without viewer and recording" :peer (format-seconds without)
               :ratio (/ with without) :goal "<= 1.05 x" :met (<= with (* 1.05 without))))))
