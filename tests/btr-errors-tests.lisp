;;;; Tests of the belief state's errors: objects removed from their world and destroyed worlds
;;;; are named (not their native handles), poses in unknown frames, :TYPES that are not lists,
;;;; degenerate point clouds.

(defpackage :cram-btr-errors-tests
  (:use :cl :fiveam))

(in-package :cram-btr-errors-tests)

(def-suite btr-errors :in cram-plans-tests:all
  :description "Errors of the belief state name what the user gave.")
(in-suite btr-errors)

(defun message-of (thunk)
  (handler-case (progn (funcall thunk) nil)
    (error (e) (princ-to-string e))))

(defmacro names (text form)
  `(let ((message (message-of (lambda () ,form))))
     (is (and message (search ,text message)) "~s should fail naming ~a, got ~s" ',form ,text message)
     (is (and message (not (search "handle" message))) "~s should not speak of handles: ~s" ',form message)))

(defun two-boxes ()
  (let ((w (make-instance 'btr:bt-reasoning-world)))
    (btr:add-object w :box 'box-a '((0 0 1) (0 0 0 1)) :size '(0.1 0.1 0.1) :mass 1)
    (btr:add-object w :box 'box-b '((1 0 1) (0 0 0 1)) :size '(0.1 0.1 0.1) :mass 1)
    w))

(test removed-objects-are-named
  (let* ((w (two-boxes)) (a (btr:object w 'box-a)) (b (btr:object w 'box-b)))
    (btr:remove-object w 'box-a)
    (names "BOX-A" (btr:attach-object b a))
    (names "BOX-A" (btr:attach-object a b))
    (names "BOX-A" (btr:detach-object b a))
    (names "BOX-A" (btr:object-color a))
    (names "BOX-A" (btr:find-objects-in-contact w a))
    (names "BOX-A" (btr:objects-in-contact-p w b a))
    (btr:destroy-world w)))

(test destroyed-worlds-are-named
  (let* ((w (two-boxes)) (b (btr:object w 'box-b)))
    (btr:destroy-world w)
    (names "destroyed" (btr:find-objects-in-contact w b))
    (names "destroyed" (btr:find-all-contacts w))
    (names "BOX-B" (btr:object-color b))))

(test poses-in-unknown-frames-are-refused
  (let ((btr:*current-bullet-world* (two-boxes))
        (cram-tf:*transformer* (make-instance 'cl-transforms-stamped:transformer)))
    (flet ((stamped (frame x)
             (cl-transforms-stamped:make-pose-stamped frame 0 (cl-transforms:make-3d-vector x 0 1)
                                                      (cl-transforms:make-identity-rotation))))
      (names "\"nowhere\"" (btr-utils:spawn-object 'bottle-9 :bottle :pose (stamped "nowhere" 0)))
      (is (null (btr:object btr:*current-bullet-world* 'bottle-9)))
      (names "\"nowhere\"" (setf (btr:pose (btr:object btr:*current-bullet-world* 'box-a))
                                 (stamped "nowhere" 0)))
      (btr-utils:spawn-object 'bottle-1 :bottle :pose (stamped "/map" 0.5))
      (is (< (abs (- 0.5 (cl-transforms:x (cl-transforms:origin
                                            (btr:pose (btr:object btr:*current-bullet-world*
                                                                  'bottle-1))))))
             1d-9))
      ;; a frame the transformer connects to the map is transformed
      (cl-transforms-stamped:set-transform
       cram-tf:*transformer*
       (cl-transforms-stamped:make-transform-stamped
        "map" "shelf" 0 (cl-transforms:make-3d-vector 2 0 0) (cl-transforms:make-identity-rotation)))
      (btr-utils:spawn-object 'bottle-2 :bottle :pose (stamped "shelf" 0.5))
      (is (< (abs (- 2.5 (cl-transforms:x (cl-transforms:origin
                                            (btr:pose (btr:object btr:*current-bullet-world*
                                                                  'bottle-2))))))
             1d-9)))
    (btr:destroy-world btr:*current-bullet-world*)))

(test types-must-be-a-list
  (let ((w (two-boxes)))
    (names "\"bottle\"" (btr:add-object w :box 'c '((0 0 2) (0 0 0 1)) :types "bottle"))
    (names ":BOTTLE" (btr:add-object w :box 'c '((0 0 2) (0 0 0 1)) :types :bottle))
    (btr:add-object w :box 'd '((0 0 2) (0 0 0 1)) :types '("bottle" :drink))
    (is (equal '(:bottle :drink) (btr:item-types (btr:object w 'd))))
    (btr:destroy-world w)))

(test degenerate-point-clouds-are-refused
  (let ((w (two-boxes)))
    (names "one line" (btr:add-object w :point-cloud 'pc '((0 0 2) (0 0 0 1))
                                      :points '((0 0 0) (0 0 0) (0 0 0) (0 0 0))))
    (names "one line" (btr:add-object w :point-cloud 'pc '((0 0 2) (0 0 0 1))
                                      :points '((0 0 0) (1 0 0) (2 0 0) (3 0 0))))
    (names "(x y z)" (btr:add-object w :point-cloud 'pc '((0 0 2) (0 0 0 1))
                                     :points '((0 0 0) (1 0 0) (0 1 0) "point")))
    (btr:add-object w :point-cloud 'pc '((0 0 2) (0 0 0 1))
                    :points '((0 0 0) (0.1 0 0) (0 0.1 0) (0 0 0.1)))
    (is (btr:object w 'pc))
    (btr:destroy-world w)))
