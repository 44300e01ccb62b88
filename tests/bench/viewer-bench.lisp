;;;; The browser viewer costs projection nothing while no page is open: move-bottle with the
;;;; viewer loaded and serving (no page) and runs being recorded, against no recording and no
;;;; viewer.

(defpackage :cram-bench.viewer
  (:use :cl :cram-bench))

(in-package :cram-bench.viewer)

(load-tool "demo.lisp" :cram-plans-demo)
(handler-bind ((warning #'muffle-warning))
  (asdf:load-system "cram-plans/viewer"))

(defun move-bottle-median (runs)
  "Median wall time of RUNS warm move-bottle projections (the first run is a warm-up)."
  (let ((quiet (make-broadcast-stream)))
    (median-seconds (lambda ()
                      (let ((r (cram-plans-demo:run-move-bottle btw-tut:*bottle-pose-in-view*
                                                                :pictures nil :log-stream quiet)))
                        (unless (getf r :success) (error "move-bottle failed: ~a" (getf r :error)))))
                    :runs runs)))

(define-benchmark viewer-idle ()
  (let* ((without (let ((cram-viewer:*record-runs* nil)
                        (cram-viewer:*start-viewer-from-debug-window* nil))
                    (cram-viewer:stop-viewer)
                    (move-bottle-median 9)))
         (with (progn (btr:viewer :port 0 :stream nil)
                      (unwind-protect (move-bottle-median 9)
                        (cram-viewer:stop-viewer)))))
    (add-row "move-bottle with the viewer serving (no page open) and the run recorded, warm median"
             (format-seconds with)
             :peer-name "the same without viewer and recording" :peer (format-seconds without)
             :ratio (/ with without) :goal "<= 1.05 x" :met (<= with (* 1.05 without)))))
