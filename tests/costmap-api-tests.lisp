;;;; Tests of CRAM's costmap API: MAKE-INSTANCE with CRAM's initargs, normalised values,
;;;; NO-COST-FUNCTIONS-REGISTERED and GEN-COSTMAP-SAMPLE-POINT.

(defpackage :cram-costmap-api-tests
  (:use :cl :fiveam))

(in-package :cram-costmap-api-tests)

(def-suite costmap-api :in cram-plans-tests:all
  :description "Location costmaps as CRAM's API makes and reads them.")
(in-suite costmap-api)

(defun instance (&rest initargs)
  (apply #'make-instance 'costmap:location-costmap
         (append initargs '(:width 2 :height 2 :resolution 0.1 :origin-x -1 :origin-y -1))))

(defun right-half (x y)
  (declare (ignore y))
  (if (> x 0) 1 0))

(test make-instance-with-cram-initargs-samples-and-merges
  (let ((c (instance)))
    (is (= 20 (costmap:costmap-columns c)))
    (is (= -1d0 (costmap:origin-x c)))
    (costmap:register-cost-function c #'right-half 'right-half)
    (let ((samples (cut:force-ll (cut:lazy-take 20 (costmap:costmap-samples c)))))
      (is (= 20 (length samples)))
      (is (every (lambda (p) (> (cl-transforms:x (cl-transforms:origin p)) 0)) samples)))
    (let* ((other (instance :cost-functions
                            (list (list 'upper (lambda (x y) (declare (ignore x)) (if (> y 0) 1 0))))))
           (merged (costmap:merge-costmaps c other)))
      (is (equal '(upper) (mapcar #'first (costmap:cost-functions other))))
      (dolist (p (cut:force-ll (cut:lazy-take 20 (costmap:costmap-samples merged))))
        (let ((o (cl-transforms:origin p)))
          (is (and (> (cl-transforms:x o) 0) (> (cl-transforms:y o) 0))))))))

(test make-instance-checks-its-initargs
  (signals error (instance :cost-functions 42))
  (signals error (instance :height-generators '(42)))
  (signals error (make-instance 'costmap:location-costmap :width -2 :height 2 :resolution 0.1
                                                          :origin-x 0 :origin-y 0)))

(test make-instance-draws-from-the-seeded-costmap-random-state
  (flet ((first-samples ()
           (costmap:seed-costmaps 11)
           (let ((c (instance)))
             (costmap:register-cost-function c #'right-half 'right-half)
             (mapcar (lambda (p) (cl-transforms:x (cl-transforms:origin p)))
                     (cut:force-ll (cut:lazy-take 5 (costmap:costmap-samples c)))))))
    (is (equal (first-samples) (first-samples)))))

(test values-are-normalised
  (let ((c (instance)))
    (costmap:register-cost-function c #'right-half 'right-half)
    (let ((m (costmap:get-cost-map c)))
      (is (< (abs (- 1 (loop for i below (array-total-size m) sum (row-major-aref m i)))) 1d-9))
      ;; 200 equal cells on the right half
      (is (< (abs (- (/ 1 200) (costmap:get-map-value c 0.5 0.5))) 1d-12))
      (is (= 0 (costmap:get-map-value c -0.5 0.5)))
      (is (= 0 (costmap:get-map-value c 5 5)) "outside the grid"))))

(test no-cost-functions-registered
  (let ((c (instance)))
    (signals costmap:no-cost-functions-registered (costmap:get-cost-map c))
    (signals costmap:no-cost-functions-registered (costmap:get-map-value c 0 0))
    (signals costmap:no-cost-functions-registered (costmap:gen-costmap-sample-point c))))

(test gen-costmap-sample-point-draws-points
  (let ((c (instance)))
    (costmap:register-cost-function c #'right-half 'right-half)
    (costmap:register-height-generator c (costmap:make-constant-height-function 0.75))
    (let ((points (loop repeat 30 collect (costmap:gen-costmap-sample-point c))))
      (is (every (lambda (p) (typep p 'cl-transforms:3d-vector)) points))
      (is (every (lambda (p) (< 0 (cl-transforms:x p) 1)) points))
      (is (every (lambda (p) (= 0.75 (cl-transforms:z p))) points)))
    (let ((p (costmap:gen-costmap-sample-point
              c :sampling-function (lambda (grid) (declare (ignore grid)) (list 15 5)))))
      (is (< (abs (- 0.55 (cl-transforms:x p))) 1d-6))
      (is (< (abs (- -0.45 (cl-transforms:y p))) 1d-6)))
    (signals error (costmap:gen-costmap-sample-point
                    c :sampling-function (lambda (grid) (declare (ignore grid)) '(99 0))))))

;;; The user's metadata, typed in their own package as the tutorials do, is read again after
;;; each change: defined, redefined, removed, and in a package made afterwards.

(test user-metadata-follows-each-change
  (let ((package (make-package (format nil "COSTMAP-USER-METADATA-~d" (random 1000000))
                               :use '(:cl :prolog))))
    (unwind-protect
         (let ((size (intern "COSTMAP-SIZE" package))
               (group (intern "MY-METADATA" package)))
           (flet ((define (n)
                    ;; as a user types it in their package
                    (eval `(prolog:def-fact-group ,group () (prolog:<- (,size ,n ,n)))))
                  (width () (costmap:width (costmap:make-location-costmap))))
             (let ((before (width)))
               (define 7)
               (is (= 7 (width)) "the user's size is used")
               (define 9)
               (is (= 9 (width)) "the redefined size is used")
               (prolog:remove-fact-group group)
               (is (= before (width)) "without the user's group, the size is the robot's again"))))
      (ignore-errors (prolog:remove-fact-group (find-symbol "MY-METADATA" package)))
      (delete-package package))))
